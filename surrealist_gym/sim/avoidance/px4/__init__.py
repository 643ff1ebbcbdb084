"""PX4-Avoidance's local planner as Aerialist runs it in SITL: the planner (:mod:`.local_planner`) and its kernels by
job: the point cloud and histogram (:mod:`.cloud`), the look-ahead tree (:mod:`.tree`, expanding nodes in
:mod:`.expansion`, smoothing costs in :mod:`.smoothing`), one planner cycle (:mod:`.cycle`) and their sizes and
constants (:mod:`.settings`)."""
