"""The track's rules against the kit's validate.py as the oracle: the same verdict, the same rule named and the same
notes on tight lanes, on (a) the kit's generators' submissions, (b) the train manifest's and the flights' scenarios
and (c) hand-broken copies of a generated submission, one per rule."""
from __future__ import annotations

import copy
import json
import math

import pytest

from surrealist_gym.forest.measures import route_distance
from surrealist_gym.forest.records import read_flight, read_train_manifest
from surrealist_gym.forest.rules import check_scenario, validate_file
from surrealist_gym.forest.scenario import Scenario
from surrealist_gym.forest.space import InvalidScenario, Rule
from tests.surrealist_gym.forest.track_kit import (
    FLIGHTS,
    GENERATED,
    MANIFEST,
    manifest_scenarios,
    notes,
    rejection,
    validate_in_process,
    validate_subprocess,
)


def our_notes(check) -> list[tuple[str, str, bool]]:
    return [(c.scenario_id, f"{c.free_width:.2f}", c.blocked) for c in check.tight_lanes]


@pytest.mark.parametrize("generator", GENERATED, ids=lambda g: f"{g[0]}-{g[1]}")
def test_a_generated_submission_is_accepted_with_the_same_notes(generator, generated):
    path = generated[generator]
    accepted, lines = validate_subprocess(path)
    check = validate_file(path)
    assert accepted and check.name in lines[-1]
    assert our_notes(check) == notes(lines)


def test_the_generators_reach_tight_and_blocked_lanes(generated):
    """The notes compared above are not all empty: the SVM generator's lanes are tight, two of them blocked."""
    checks = validate_file(generated[("svm_generator", 7)]).tight_lanes
    assert len(checks) == 15 and sum(c.blocked for c in checks) == 2


def test_each_manifest_and_flight_scenario_gets_validate_pys_verdict_and_note(oracle, generated, tmp_path):
    validate, _ = oracle
    base = json.loads(generated[("random_baseline", 7)].read_text())
    records = {r.scenario.id: r for r in read_train_manifest(MANIFEST)}
    flown = [read_flight(p) for p in FLIGHTS]
    flown = [f.scenario(records[f.id].scenario.seed, records[f.id].scenario.obstacle.height).to_json() for f in flown]
    path, tight = tmp_path / "one.json", 0
    for obj in manifest_scenarios() + flown:
        path.write_text(json.dumps(dict(base, scenarios=[obj] + base["scenarios"][1:])))
        accepted, lines = validate_in_process(validate, path)
        alone = check_scenario(Scenario.from_json(obj))
        assert accepted and our_notes(validate_file(path)) == notes(lines)
        expected = [n for n in notes(lines) if n[0] == obj["id"]]
        assert ([(alone.scenario_id, f"{alone.free_width:.2f}", alone.blocked)] if alone.tight else []) == expected
        tight += alone.tight
    assert tight == 39  # lanes validate.py notes among the 255 (each compared above)


def test_the_manifests_scenarios_twenty_at_a_time(oracle, tmp_path):
    validate, _ = oracle
    scenarios = manifest_scenarios()
    path = tmp_path / "twenty.json"
    for start in range(0, len(scenarios) - 19, 20):
        path.write_text(json.dumps({"submission": "manifest", "scenarios": scenarios[start:start + 20]}))
        accepted, lines = validate_in_process(validate, path)
        check = validate_file(path)
        assert accepted and our_notes(check) == notes(lines) and check.recipes == 20


# --- hand-broken copies: one per rule -----------------------------------------------------------------------------
def first(scenarios: list, wanted) -> dict:
    return next(s for s in scenarios if wanted(s))


def without_poles(s: dict) -> dict:
    s["obstacle"]["xy"] = []
    return s


def sharp_last_turn(doc: dict) -> None:
    """In the first scenario with room for it, the last waypoint moved so that the turn before it is 170 deg, its
    leg as long as before; that scenario's poles taken away (the route's rules alone)."""
    for s in doc["scenarios"]:
        if len(s["patrol"]) >= 3:
            *_, a, b, c = s["patrol"]
            heading, length = math.atan2(b[1] - a[1], b[0] - a[0]), math.dist(b, c)
            for turn in (math.radians(170), -math.radians(170)):
                end = [b[0] + length * math.cos(heading + turn), b[1] + length * math.sin(heading + turn)]
                if max(map(abs, end)) < s["area"] - 3.5:
                    s["patrol"][-1] = end
                    without_poles(s)
                    return
    raise AssertionError("no room for the turn")


def short_last_leg(s: dict) -> None:
    *_, b, c = s["patrol"]
    s["patrol"][-1] = [b[0] + 5 * (c[0] - b[0]) / math.dist(b, c), b[1] + 5 * (c[1] - b[1]) / math.dist(b, c)]


def pole_off_the_lane(s: dict) -> None:
    """Pole 0 moved where it breaks the lane alone: clear of the waypoints and the other poles, inside the field."""
    patrol, others = s["patrol"], s["obstacle"]["xy"][1:]
    edge = int(s["area"]) - 1
    for x in range(-edge, edge + 1):
        for y in range(-edge, edge + 1):
            if (route_distance((x, y), patrol) > s["corridor"] / 2 + 0.5 and min(math.dist((x, y), w) for w in patrol)
                    > 3.5 and all(math.dist((x, y), q) > 2 for q in others)):
                s["obstacle"]["xy"][0] = [float(x), float(y)]
                return
    raise AssertionError("no place off the lane")


def pole_beside_pole_0(s: dict) -> None:
    """Pole 1 moved 1.0 m from pole 0, where it breaks no rule but the separation."""
    patrol, (p, *rest) = s["patrol"], s["obstacle"]["xy"]
    for step in range(24):
        q = (p[0] + math.cos(step * math.pi / 12), p[1] + math.sin(step * math.pi / 12))
        if (route_distance(q, patrol) < s["corridor"] / 2 - 0.01 and min(math.dist(q, w) for w in patrol) > 3.01
                and all(math.dist(q, o) > 1.51 for o in rest[1:])):
            s["obstacle"]["xy"][1] = list(q)
            return
    raise AssertionError("no place beside pole 0")


def recipes(doc: dict, int_corridor: bool = False) -> None:
    """Four recipes, five seeds each; with ``int_corridor``, one copy writes its integral corridor as an integer."""
    four = [first(doc["scenarios"], lambda s: float(s["corridor"]).is_integer())] + doc["scenarios"][1:4]
    doc["scenarios"] = [dict(four[k % 4], id=f"s{k:03d}", seed=1000 + k) for k in range(20)]
    if int_corridor:
        doc["scenarios"][0]["corridor"] = int(doc["scenarios"][0]["corridor"])


def copy_reordered(doc: dict) -> None:
    """The scenario after the first with two poles or more made its copy, with a note and its poles reversed."""
    k = next(k for k, s in enumerate(doc["scenarios"]) if len(s["obstacle"]["xy"]) > 1)
    original = doc["scenarios"][k]
    doc["scenarios"][k + 1] = dict(original, id=doc["scenarios"][k + 1]["id"], note="a copy", obstacle=dict(
        original["obstacle"], xy=original["obstacle"]["xy"][::-1]))


def wrapped_in_a_list(doc: dict) -> None:
    """Stands for the document put in a list (the test does it)."""


def scenario(k: int, edit):
    """An edit of the document's scenario ``k``."""
    return lambda doc: edit(doc["scenarios"][k])


def poled(n: int, edit):
    """An edit of the first scenario with at least ``n`` poles."""
    return lambda doc: edit(first(doc["scenarios"], lambda s: len(s["obstacle"]["xy"]) >= n))


def routed(n: int, edit):
    """An edit of the first scenario with at least ``n`` waypoints, its poles taken away (the route's rules alone)."""
    return lambda doc: edit(without_poles(first(doc["scenarios"], lambda s: len(s["patrol"]) >= n)))


BROKEN = [
    ("text-truncated", None, Rule.JSON, None),
    ("a-list", wrapped_in_a_list, Rule.SUBMISSION_SHAPE, None),
    ("scenarios-an-object", lambda doc: doc.update(scenarios={}), Rule.SUBMISSION_SHAPE, None),
    ("name-with-space", lambda doc: doc.update(submission="svm generator"), Rule.SUBMISSION_NAME, None),
    ("19-scenarios", lambda doc: doc["scenarios"].pop(), Rule.COUNT, None),
    ("21-scenarios", lambda doc: doc["scenarios"].append(dict(doc["scenarios"][0], id="s020", seed=5)), Rule.COUNT,
     None),
    ("scenario-a-string", lambda doc: doc["scenarios"].__setitem__(3, "s003"), Rule.SCENARIO_OBJECT, None),
    ("id-with-space", scenario(2, lambda s: s.update(id="s 2")), Rule.SCENARIO_ID, None),
    ("id-a-number", scenario(2, lambda s: s.update(id=2)), Rule.SCENARIO_ID, None),
    ("id-twice", scenario(1, lambda s: s.update(id="s000")), Rule.DUPLICATE_ID, None),
    ("seed-a-float", scenario(0, lambda s: s.update(seed=7.0)), Rule.SEED_INTEGER, None),
    ("seed-missing", scenario(0, lambda s: s.pop("seed")), Rule.SEED_INTEGER, None),
    ("wind-missing", scenario(4, lambda s: s.pop("wind")), Rule.NUMBER, "wind"),
    ("density-nan", scenario(4, lambda s: s.update(density=float("nan"))), Rule.NUMBER, "density"),
    ("alt-a-string", scenario(4, lambda s: s.update(alt="1.5")), Rule.NUMBER, "alt"),
    ("area-true", scenario(4, lambda s: s.update(area=True)), Rule.NUMBER, "area"),
    ("seed-0", scenario(5, lambda s: s.update(seed=0)), Rule.RANGE, "seed"),
    ("density-0.2", scenario(5, lambda s: s.update(density=0.2)), Rule.RANGE, "density"),
    ("area-45", scenario(5, lambda s: s.update(area=45.0)), Rule.RANGE, "area"),
    ("corridor-13", scenario(5, lambda s: s.update(corridor=13)), Rule.RANGE, "corridor"),
    ("ego_max_vel-4", scenario(5, lambda s: s.update(ego_max_vel=4.0)), Rule.RANGE, "ego_max_vel"),
    ("wind-9", scenario(5, lambda s: s.update(wind=9.0)), Rule.RANGE, "wind"),
    ("alt-0.4", scenario(5, lambda s: s.update(alt=0.4)), Rule.RANGE, "alt"),
    ("voxel-0.3", scenario(5, lambda s: s.update(voxel=0.3)), Rule.RANGE, "voxel"),
    ("radius-0.2", scenario(5, lambda s: s["obstacle"].update(radius=0.2)), Rule.RANGE, "radius"),
    ("height-6", scenario(5, lambda s: s["obstacle"].update(height=6)), Rule.RANGE, "height"),
    ("one-waypoint", scenario(6, lambda s: s.update(patrol=s["patrol"][:1])), Rule.WAYPOINTS, None),
    ("patrol-a-string", scenario(6, lambda s: s.update(patrol="north")), Rule.WAYPOINTS, None),
    ("waypoint-of-one", scenario(6, lambda s: s["patrol"].__setitem__(1, [1.0])), Rule.WAYPOINT_FORM, None),
    ("waypoints-off-the-edge", routed(2, lambda s: s.update(area=round(max(abs(c) for w in s["patrol"] for c in w)
                                                                      + 2.5, 2))), Rule.EDGE_MARGIN, None),
    ("a-5-m-leg", routed(2, short_last_leg), Rule.LEG, None),
    ("a-170-deg-turn", sharp_last_turn, Rule.TURN, None),
    ("obstacle-boxes", scenario(7, lambda s: s["obstacle"].update(type="boxes")), Rule.OBSTACLE_TYPE, None),
    ("obstacle-missing", scenario(7, lambda s: s.pop("obstacle")), Rule.OBSTACLE_TYPE, None),
    ("radius-missing", scenario(7, lambda s: s["obstacle"].pop("radius")), Rule.OBSTACLE_NUMBER, "radius"),
    ("height-null", scenario(7, lambda s: s["obstacle"].update(height=None)), Rule.OBSTACLE_NUMBER, "height"),
    ("11-poles", poled(1, lambda s: s["obstacle"].update(xy=s["obstacle"]["xy"][:1] * 11)), Rule.POLE_COUNT, None),
    ("poles-an-object", scenario(7, lambda s: s["obstacle"].update(xy={})), Rule.POLE_COUNT, None),
    ("pole-of-one", poled(1, lambda s: s["obstacle"]["xy"].__setitem__(0, [1.0])), Rule.POLE_FORM, None),
    ("pole-off-the-field", poled(1, lambda s: s["obstacle"]["xy"].__setitem__(0, [s["area"] + 1, 0.0])),
     Rule.POLE_EXTENT, None),
    ("pole-off-the-lane", poled(1, pole_off_the_lane), Rule.POLE_LANE, None),
    ("pole-by-a-waypoint", poled(1, lambda s: s["obstacle"]["xy"].__setitem__(
        0, [s["patrol"][1][0] + 0.5, s["patrol"][1][1]])), Rule.POLE_WAYPOINT, None),
    ("poles-1-m-apart", poled(2, pole_beside_pole_0), Rule.POLE_SEPARATION, None),
    ("unknown-field", scenario(8, lambda s: s.update(colour="red")), Rule.UNKNOWN_FIELD, None),
    ("unknown-obstacle-field", scenario(8, lambda s: s["obstacle"].update(shape="round")),
     Rule.UNKNOWN_OBSTACLE_FIELD, None),
    ("a-copy-but-its-id", lambda doc: doc["scenarios"].__setitem__(1, dict(doc["scenarios"][0], id="s001")),
     Rule.DUPLICATE_SCENARIO, None),
    ("a-copy-but-its-id-note-and-pole-order", copy_reordered, Rule.DUPLICATE_SCENARIO, None),
    ("four-recipes", recipes, Rule.RECIPES, None),
]


@pytest.mark.parametrize("name, edit, rule, field", BROKEN, ids=[b[0] for b in BROKEN])
def test_a_broken_copy_gets_validate_pys_verdict_and_rule(name, edit, rule, field, generated, tmp_path):
    doc = json.loads(generated[("svm_generator", 7)].read_text())
    path = tmp_path / "submission.json"
    if edit is None:
        path.write_text(json.dumps(doc)[:-40])
    else:
        edit(doc)
        path.write_text(json.dumps([doc] if edit is wrapped_in_a_list else doc))
    accepted, lines = validate_subprocess(path)
    assert not accepted
    named, sid, named_field = rejection(lines)
    assert named == rule.name and named_field == field, lines
    with pytest.raises(InvalidScenario) as err:
        validate_file(path)
    message = str(err.value)
    assert err.value.rule is rule, message
    assert message.startswith(f"{path}: ") and "\n" not in message
    assert sid is None or f"scenario {sid}" in message
    assert field is None or field in message


@pytest.mark.parametrize("change", ["note", "int-corridor"])
def test_what_validate_py_accepts_of_what_looks_broken(change, generated, tmp_path):
    """Provenance fields are allowed; and its fingerprints tell an integer from a float, so a corridor written 2
    where another copy writes 2.0 makes a fifth recipe."""
    doc = json.loads(generated[("svm_generator", 7)].read_text())
    if change == "note":
        doc["scenarios"][0].update(note="hand-made", stratum="tight", generator="svm", turn_total_deg=90)
    else:
        recipes(doc, int_corridor=True)
    path = tmp_path / "submission.json"
    path.write_text(json.dumps(doc))
    accepted, lines = validate_subprocess(path)
    check = validate_file(path)
    assert accepted and our_notes(check) == notes(lines)
    assert check.recipes == (5 if change == "int-corridor" else 20)


def test_a_scenario_is_checked_alone_with_the_file_scenario_and_field_named(generated):
    doc = json.loads(generated[("svm_generator", 7)].read_text())
    obj = copy.deepcopy(doc["scenarios"][9])
    obj["wind"] = 8.5
    with pytest.raises(InvalidScenario, match=r"^in.json: scenario s009: wind: 8.5 out of \[0, 8\] m/s$") as err:
        check_scenario(Scenario.from_json(obj), "in.json")
    assert err.value.rule is Rule.RANGE
