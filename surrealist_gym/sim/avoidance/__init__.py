"""Obstacle avoidance: what the run loop asks of a planner (:mod:`.planner`), the reactive planner tuned to the real
PX4 Vision (:mod:`.reactive`, its compiled cycle :mod:`.reactive_cycle`) and PX4-Avoidance as Aerialist runs it
(:mod:`.px4`)."""
