import pytest

import surrealist_gym as sg
from surrealist_gym.mutators import AUTHORS_ORDER, Mutator, MutatorKind, default_mutators
from tests.conftest import EXPERIMENTS


@pytest.fixture(scope="module")
def seed():
    return sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")


def test_defaults_follow_table1(seed):
    move, rotate = Mutator(0, MutatorKind.MOVE_X), Mutator(0, MutatorKind.ROTATE)
    assert (move.default_step, move.min_step, move.default_value) == (4.0, 0.1, 0.0)
    assert (rotate.default_step, rotate.min_step) == (30.0, 0.5)
    assert [m.kind.value for m in default_mutators(seed)] == ["y", "x", "r", "sy", "sx", "sz"]


def test_apply_is_relative_and_immutable(seed):
    moved = Mutator(0, MutatorKind.MOVE_Y).apply(seed, 2.5)
    assert moved.obstacles[0].y == pytest.approx(1.74 + 2.5) and seed.obstacles[0].y == 1.74
    assert Mutator(0, MutatorKind.MOVE_Y).apply(seed, 0.0) is seed
    bigger = Mutator(0, MutatorKind.RESIZE_H).apply(seed, 2.0)
    assert (bigger.obstacles[0].h, bigger.obstacles[0].x) == (5.0, seed.obstacles[0].x)  # centre kept
    turned = Mutator(0, MutatorKind.ROTATE).apply(seed, -30)
    assert turned.obstacles[0].r == pytest.approx(128.8)


def test_invalid_results_are_rejected(seed):
    with pytest.raises(sg.InvalidTestCase, match=r"obstacle0.sx by -4: .*'l' must be positive"):
        Mutator(0, MutatorKind.RESIZE_L).apply(seed, -4)
    two = sg.load_test(EXPERIMENTS / "rq2-seed.yaml")
    with pytest.raises(sg.InvalidTestCase, match="overlap"):
        Mutator(0, MutatorKind.MOVE_X).apply(two, -23.5625)
    with pytest.raises(sg.InvalidTestCase, match="has 1 obstacle"):
        Mutator(3, MutatorKind.MOVE_X).apply(seed, 1)


def test_move_only_on_first_obstacle():
    two = sg.load_test(EXPERIMENTS / "rq2-seed.yaml")
    mutators = default_mutators(two, kinds=(MutatorKind.MOVE_X, MutatorKind.MOVE_Y), obstacles=[0])
    assert [m.name for m in mutators] == ["obstacle0.x", "obstacle0.y"]
    assert len(AUTHORS_ORDER) == 6


def test_valid_range_keeps_the_size_positive(seed):
    resize = Mutator(0, MutatorKind.RESIZE_L)
    low, high = resize.valid_range(seed)
    assert (low, high) == (pytest.approx(0.1 - 3.0), 20.0)
    assert resize.apply(seed, low).obstacles[0].l == pytest.approx(0.1)
    assert Mutator(0, MutatorKind.MOVE_X).valid_range(seed) == (-20.0, 20.0)
    assert Mutator(0, MutatorKind.ROTATE).valid_range(seed) == (-180.0, 180.0)
