"""The ICST 2027 UAV perception testing track (``../shared/TRACK2027.md``): its inputs and rules.

:mod:`.space` holds the track's limits and the names of its rules; :mod:`.scenario` reads and writes a scenario and
a ``submission.json`` as immutable values; :mod:`.rules` accepts a submission exactly when the track's
``validate.py`` does; :mod:`.measures` gives ``preflight.py``'s measures; :mod:`.records` reads the kit's flight
records (``flights/*.json``) and the train manifest (``data/train/manifest.jsonl``); :mod:`.scoring` scores flights
as the track does (the rank key ``mech_rate``, its diagnostics, the noise band between two entries).
"""
from .measures import Band, Preflight, band, free_lateral_width, input_div, nearest_pole_to_route, preflight
from .rules import ScenarioCheck, SubmissionCheck, check_scenario, check_submission, validate_file
from .scenario import Poles, Scenario, Submission, read_submission, write_submission
from .scoring import EntryScore, Evaluation, FlightOutcome, evaluate, mech_rate, noise_band, score_entry
from .space import InvalidScenario, Rule

__all__ = ["Band", "EntryScore", "Evaluation", "FlightOutcome", "InvalidScenario", "Poles", "Preflight", "Rule",
           "Scenario", "ScenarioCheck", "Submission", "SubmissionCheck", "band", "check_scenario", "check_submission",
           "evaluate", "free_lateral_width", "input_div", "mech_rate", "nearest_pole_to_route", "noise_band",
           "preflight", "read_submission", "score_entry", "validate_file", "write_submission"]
