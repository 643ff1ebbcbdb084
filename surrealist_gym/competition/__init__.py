"""The UAV Testing Competition on surrealist-gym: its rules, tests and suites, their scoring, and its tools.

- :mod:`~surrealist_gym.competition.rules`: case studies, the rules on boxes, a run's points, the layout mutators;
- :mod:`~surrealist_gym.competition.feasibility`: whether a free corridor joins each leg's start and goal;
- :mod:`~surrealist_gym.competition.case_study_env`: ``Surrealist-CaseStudy-v1``, a case study as a search problem;
- :mod:`~surrealist_gym.competition.suite`, :mod:`~surrealist_gym.competition.suite_env`,
  :mod:`~surrealist_gym.competition.suite_export`: suites of distinct failures, the wrapper that keeps one from any
  search, and a suite as Aerialist files;
- :mod:`~surrealist_gym.competition.reevaluation` (its report: ``reports/``) and
  :mod:`~surrealist_gym.competition.scoring`: re-flying tests and scoring folders as an edition did;
- :mod:`~surrealist_gym.competition.compete`: a competition tool's own ``cli.py`` run on our simulator (the
  Aerialist bridge); :mod:`~surrealist_gym.competition.export_tool`: surrealist-gym as such a tool.

Built on the core (testcase, mutators, evaluation, executors, sim, the envs' base); the core does not import it.
Nothing is imported here, so loading one module loads only what it needs.
"""
