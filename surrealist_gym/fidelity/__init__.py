"""Fidelity: how far the simulated UAV agrees with another system, and the UAV fitted to real logs.

- :mod:`~surrealist_gym.fidelity.labels`: labelled sets of Aerialist tests (a tests CSV on a base mission, or a
  folder of YAMLs with a labels file);
- :mod:`~surrealist_gym.fidelity.measure`: fly a labelled set and report the agreement (``surrealist fidelity``);
- :mod:`~surrealist_gym.fidelity.calibration`: fit a UAV profile's settings to flight logs (``surrealist
  calibrate``);
- :mod:`~surrealist_gym.fidelity.verdict_features` and :mod:`~surrealist_gym.fidelity.verdict`: a model of PX4's
  verdict from our runs of a test (``surrealist predict``).

Built on the core (executors, sim, the Aerialist format); the core does not import it.
"""
