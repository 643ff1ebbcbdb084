"""The track's scenario and submission.json as values: read and written back exactly (the kit's generators' output,
the train manifest's and the flights' scenarios), what we write accepted by the kit's validate.py as the original,
immutable, and bad form refused in one line naming the file, the scenario and the field."""
from __future__ import annotations

import dataclasses
import json

import pytest

from surrealist_gym.errors import InvalidTestCase
from surrealist_gym.forest.records import read_flight, read_train_manifest
from surrealist_gym.forest.scenario import Poles, Scenario, Submission, read_submission, write_submission
from surrealist_gym.forest.space import InvalidScenario, Rule
from tests.surrealist_gym.forest.track_kit import FLIGHTS, GENERATED, MANIFEST, manifest_scenarios, validate_subprocess


def exact(value) -> str:
    """A JSON value as text that tells 6 from 6.0 and ignores key order."""
    return json.dumps(value, sort_keys=True)


@pytest.mark.parametrize("generator", GENERATED, ids=lambda g: f"{g[0]}-{g[1]}")
def test_a_generated_submission_is_written_back_as_read_and_validate_py_says_the_same(generator, generated, tmp_path):
    path = generated[generator]
    original = json.loads(path.read_text())
    submission = read_submission(path)
    assert len(submission.scenarios) == 20 and submission.name == original["submission"]
    assert exact(submission.to_json()) == exact(original)
    ours = tmp_path / "submission.json"
    write_submission(submission, ours)
    assert exact(json.loads(ours.read_text())) == exact(original)
    assert read_submission(ours) == submission
    assert validate_subprocess(ours) == validate_subprocess(path)
    assert validate_subprocess(ours)[0]


def test_the_random_baselines_extra_top_level_fields_survive(generated):
    submission = read_submission(generated[("random_baseline", 7)])
    assert submission.extra == {"generator": "random", "gen_seed": 7}


def test_the_same_submission_gives_the_same_bytes(generated, tmp_path):
    submission = read_submission(generated[("svm_generator", 7)])
    write_submission(submission, tmp_path / "a.json")
    write_submission(read_submission(tmp_path / "a.json"), tmp_path / "b.json")
    assert (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes() == submission.to_text().encode()


def test_the_manifests_and_the_flights_scenarios_are_written_back_as_read(kit):
    raw = manifest_scenarios()
    assert len(raw) == 251
    for obj in raw:
        assert exact(Scenario.from_json(obj).to_json()) == exact(obj)
    records = {r.scenario.id: r for r in read_train_manifest(MANIFEST)}
    for path in FLIGHTS:
        flight = read_flight(path)
        record = records[flight.id]
        scenario = flight.scenario(record.scenario.seed, record.scenario.obstacle.height)
        assert scenario == record.scenario
        assert scenario.patrol == tuple(map(tuple, json.loads(path.read_text())["route"]))


def test_an_integer_stays_an_integer_and_provenance_is_kept():
    obj = {"id": "s000", "seed": 41835, "area": 20, "voxel": 0.1, "corridor": 6, "density": 0.0364, "wind": 0,
           "ego_max_vel": 1.56, "alt": 2.086, "patrol": [[8, 10.92], [11.65, -5]], "note": "hand-written",
           "obstacle": {"type": "poles", "xy": [[9.29, 6.3]], "radius": 0.06, "height": 3}}
    scenario = Scenario.from_json(obj)
    assert exact(scenario.to_json()) == exact(obj)
    assert scenario.to_json()["corridor"] == 6 and isinstance(scenario.to_json()["corridor"], int)
    assert scenario.metadata == {"note": "hand-written"}


def test_values_are_immutable(generated):
    submission = read_submission(generated[("random_baseline", 7)])
    scenario = submission.scenarios[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        scenario.wind = 1.0
    with pytest.raises(TypeError):
        submission.extra["gen_seed"] = 8
    assert isinstance(scenario.patrol, tuple) and isinstance(scenario.obstacle.xy, tuple)
    assert isinstance(submission.scenarios, tuple)
    moved = dataclasses.replace(scenario, wind=1.0)
    assert moved.wind == 1.0 and moved != scenario and {moved, scenario} == {scenario, moved}  # hashable


def base_scenario() -> dict:
    return {"id": "s007", "seed": 41835, "area": 20.0, "voxel": 0.1, "corridor": 4.5, "density": 0.0364, "wind": 1.7,
            "ego_max_vel": 1.56, "alt": 2.086, "patrol": [[8.44, 10.92], [11.65, -5.22]],
            "obstacle": {"type": "poles", "xy": [[9.29, 6.3]], "radius": 0.06, "height": 3.0}}


@pytest.mark.parametrize("edit, rule, field", [
    (lambda s: s.pop("wind"), Rule.NUMBER, "wind"),
    (lambda s: s.update(alt=float("nan")), Rule.NUMBER, "alt"),
    (lambda s: s.update(density=True), Rule.NUMBER, "density"),
    (lambda s: s.update(seed=7.0), Rule.SEED_INTEGER, "seed"),
    (lambda s: s.update(id="s 7"), Rule.SCENARIO_ID, "id"),
    (lambda s: s.update(patrol="north"), Rule.WAYPOINTS, "patrol"),
    (lambda s: s["patrol"].append([1.0]), Rule.WAYPOINT_FORM, "patrol[2]"),
    (lambda s: s.update(obstacle={"type": "boxes"}), Rule.OBSTACLE_TYPE, "obstacle"),
    (lambda s: s["obstacle"].pop("radius"), Rule.OBSTACLE_NUMBER, "obstacle.radius"),
    (lambda s: s["obstacle"].update(xy={"a": 1}), Rule.POLE_COUNT, "obstacle.xy"),
    (lambda s: s["obstacle"]["xy"].append([1.0, "2"]), Rule.POLE_FORM, "obstacle.xy[1]"),
    (lambda s: s["obstacle"].update(shape="round"), Rule.UNKNOWN_OBSTACLE_FIELD, "shape"),
    (lambda s: s.update(colour="red"), Rule.UNKNOWN_FIELD, "colour"),
], ids=lambda v: v.name if isinstance(v, Rule) else None)
def test_bad_form_is_one_line_naming_the_file_the_scenario_and_the_field(edit, rule, field, tmp_path):
    scenario = base_scenario()
    edit(scenario)
    path = tmp_path / "submission.json"
    path.write_text(json.dumps({"submission": "mine", "scenarios": [scenario]}))
    with pytest.raises(InvalidScenario) as err:
        read_submission(path)
    message = str(err.value)
    assert isinstance(err.value, InvalidTestCase) and err.value.rule is rule
    assert "\n" not in message and message.startswith(f"{path}: scenario ") and field in message
    assert ("s 7" if rule is Rule.SCENARIO_ID else "s007") in message or "scenario 0" in message


@pytest.mark.parametrize("text, rule", [
    ("{\"submission\": \"mine\", \"scenarios\": [", Rule.JSON),
    ("[]", Rule.SUBMISSION_SHAPE),
    ("{\"submission\": \"mine\", \"scenarios\": {}}", Rule.SUBMISSION_SHAPE),
    ("{\"submission\": \"my gen\", \"scenarios\": []}", Rule.SUBMISSION_NAME),
    ("{\"submission\": \"mine\", \"scenarios\": [\"s000\"]}", Rule.SCENARIO_OBJECT),
], ids=lambda v: v.name if isinstance(v, Rule) else None)
def test_a_bad_document_is_one_line_naming_the_file(text, rule, tmp_path):
    path = tmp_path / "submission.json"
    path.write_text(text)
    with pytest.raises(InvalidScenario) as err:
        read_submission(path)
    assert err.value.rule is rule and str(err.value).startswith(f"{path}: ") and "\n" not in str(err.value)


def test_a_missing_file_is_one_line(tmp_path):
    with pytest.raises(InvalidScenario, match="cannot read submission"):
        read_submission(tmp_path / "none.json")


def test_values_built_in_code_are_checked_too():
    with pytest.raises(InvalidScenario, match="scenario s1: patrol\\[1\\]: expected \\[x, y\\]") as err:
        Scenario("s1", 3, 20.0, 0.1, 6.0, 0.03, 0.0, 2.0, 1.5, ((0.0, 0.0), (1.0,)), Poles((), 0.05, 3.0))
    assert err.value.rule is Rule.WAYPOINT_FORM
    with pytest.raises(InvalidScenario) as err:
        Submission("bad name", ())
    assert err.value.rule is Rule.SUBMISSION_NAME
