"""The kit's flight records and the train manifest's records, read into values, against what TRACK2027.md sections 3
and 6 say of them and against each other."""
from __future__ import annotations

import json
from collections import Counter

import pytest

from surrealist_gym.errors import LogFormatError
from surrealist_gym.forest.records import (
    CollectionStatus,
    Mechanism,
    Outcome,
    RoutePhase,
    Species,
    StruckObject,
    VehiclePart,
    read_flight,
    read_train_manifest,
)
from tests.surrealist_gym.forest.track_kit import FLIGHTS, MANIFEST


@pytest.fixture(scope="module")
def records(kit):
    return read_train_manifest(MANIFEST)


def test_the_train_manifest_holds_what_track2027_counts(records):
    assert len(records) == 267 and {r.split for r in records} == {"train"}
    assert sum(r.counts for r in records) == 245
    assert Counter(r.outcome for r in records) == {Outcome.GOAL: 137, Outcome.COLLISION: 108, Outcome.FAILED: 19,
                                                   Outcome.TIMEOUT: 3}
    # TRACK2027.md: "245 valid and admissible; 108 of those collided": 108 collided in all, 107 of them count
    assert sum(r.outcome is Outcome.COLLISION for r in records if r.counts) == 107
    strikes = Counter()
    for r in records:
        for m in r.mechanism or ():
            strikes.update([m.struck, m.part, m.phase])
    assert strikes == {StruckObject.POLE: 67, StruckObject.TREE: 63, StruckObject.TERRAIN: 9, VehiclePart.ROTOR: 88,
                       VehiclePart.BODY: 51, RoutePhase.LEG: 77, RoutePhase.TURN: 62}
    assert len({m for r in records for m in r.mechanism or ()}) == 10
    unread = [r for r in records if r.mechanism is None]
    assert len(unread) == 9 and all(r.outcome is Outcome.COLLISION for r in unread)
    assert all(r.mechanism == () for r in records if r.outcome is not Outcome.COLLISION)


def test_a_manifest_record_reads_its_blocks(records):
    first = records[0]
    assert first.scenario.id == "c0006" and first.scenario.seed == 91431 and first.scenario.corridor == 2.0
    assert first.scene.trees_placed == 58 and first.scene.density_delivered == 0.03625 and not first.scene.shortfall
    assert first.collection_status is CollectionStatus.VALID and first.stack["gt_odom"] is True
    assert first.wall_s == 153.1 and first.failure_reason is None
    with pytest.raises(TypeError):
        first.stack["gt_odom"] = False


def test_the_flights_agree_with_their_manifest_records(records):
    by_id = {r.scenario.id: r for r in records}
    assert [p.stem for p in FLIGHTS] == ["c0017", "c0071", "c0073", "c0304"]
    species = Counter()
    for path in FLIGHTS:
        flight = read_flight(path)
        record = by_id[flight.id]
        assert flight.outcome is record.outcome is Outcome.COLLISION and flight.mechanism == record.mechanism
        assert flight.scenario(record.scenario.seed, record.scenario.obstacle.height) == record.scenario
        assert len(flight.trees) == record.scene.trees_placed and len(flight.poles) == record.scene.poles_placed
        assert all(0.5 < t.scale < 1.0 for t in flight.trees)
        species.update(t.species for t in flight.trees)
        steps = [round(b.t - a.t, 6) for a, b in zip(flight.track, flight.track[1:])]
        assert set(steps) == {0.1} and flight.track[-1].t <= flight.t_end
        assert flight.lane[0] == flight.route[0] and flight.lane[-1] == flight.route[-1]
    assert set(species) == set(Species)
    assert read_flight(FLIGHTS[0]).mechanism == (Mechanism(StruckObject.POLE, VehiclePart.ROTOR, RoutePhase.TURN),)


def test_records_of_another_split_are_skipped(kit, tmp_path):
    lines = MANIFEST.read_text().splitlines()[:3]
    other = json.loads(lines[1])
    other["split"] = "private"
    path = tmp_path / "manifest.jsonl"
    path.write_text("\n".join([lines[0], json.dumps(other), lines[2]]) + "\n")
    assert [r.scenario.id for r in read_train_manifest(path)] == [json.loads(lines[i])["scenario"] for i in (0, 2)]


@pytest.mark.parametrize("edit, names", [
    (lambda r: r.update(outcome="crashed"), ["outcome", "goal"]),
    (lambda r: r["params"].pop("wind"), ["params.wind", "missing"]),
    (lambda r: r["scene"].update(trees_placed=5.5), ["scene.trees_placed", "integer"]),
    (lambda r: r.update(mechanism=[["pole", "wing", "leg"]]), ["mechanism", "body|rotor"]),
    (lambda r: r.update(patrol=[[1.0, 2.0], [3.0]]), ["patrol[1]"]),
])
def test_a_bad_manifest_record_is_one_line_naming_the_line_and_field(kit, tmp_path, edit, names):
    lines = MANIFEST.read_text().splitlines()[:2]
    bad = json.loads(lines[1])
    edit(bad)
    path = tmp_path / "manifest.jsonl"
    path.write_text(lines[0] + "\n" + json.dumps(bad) + "\n")
    with pytest.raises(LogFormatError) as err:
        read_train_manifest(path)
    assert str(err.value).startswith(f"{path}:2: ") and "\n" not in str(err.value)
    assert all(name in str(err.value) for name in names), str(err.value)


def test_a_bad_flight_record_is_one_line_naming_the_field(kit, tmp_path):
    flight = json.loads(FLIGHTS[0].read_text())
    flight["trees"][3][3] = "oak"
    path = tmp_path / "flight.json"
    path.write_text(json.dumps(flight))
    with pytest.raises(LogFormatError, match=r"flight.json: trees\[3\].species: expected one of \['birch'"):
        read_flight(path)
    flight = json.loads(FLIGHTS[0].read_text())
    flight["corridor"] = 9.0
    path.write_text(json.dumps(flight))
    with pytest.raises(LogFormatError, match=r"flight.json: corridor: expected params.corridor \(3.0\), got 9.0"):
        read_flight(path)
