"""The competition's commands: ``evaluate`` (re-fly and score suites), ``compete`` (run a tool), ``leaderboard`` (rank
tools) and ``export-tool`` (write one)."""
