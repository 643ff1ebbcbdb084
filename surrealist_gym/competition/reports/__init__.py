"""The competition's reports: a re-evaluation's (:mod:`.evaluation`), a leaderboard's (:mod:`.leaderboard`), their
figures (:mod:`.plots`) and numbers as the reports write them (:mod:`.tables`)."""
