"""The settings of pre-screening (:class:`PrescreenConfig`): which screening rule, its margin, racing's stages,
retraining, and how skips are told to the inner agent (:mod:`surrogates.prescreen`, docs/surrogates.md)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

RULES = ("auto", "lowfi", "ei", "pi", "none")


class SkipAccounting(str, Enum):
    """How a skipped (or raced-out) candidate is told to the inner agent; the env's budget counts real simulations
    in every case."""

    MEMO = "memo"  #: as a free memo answer: the greedy does not charge it to its local budgets
    EVALUATION = "evaluation"  #: as an evaluation: the inner agent plans its own budgets as without screening
    BUDGET = "budget"  #: as an evaluation spent from the budget the inner agent sees, so it walks and stops as
    #: without screening, having simulated less; the real budget left is unused or goes to ``verify_stop``


@dataclass(frozen=True, slots=True)
class PrescreenConfig:
    """How candidates are screened and the model retrained.

    Attributes:
        rule: ``auto``, ``lowfi`` (low-fidelity shortfall), ``ei`` (expected improvement), ``pi``
            (probability of improvement) or ``none`` (skip nothing: only race, with ``first_runs``); see the
            module docstring.
        margin: ``lowfi``: skip when the low-fidelity fitness is below the incumbent's by more than this (in
            fitness units); None calibrates it on the model's training data (see ``miss_rate``).
        miss_rate: share of the past real improvements whose low-fidelity shortfall may exceed the calibrated
            margin.
        threshold: EI below ``threshold`` x std of the training targets (``ei``), or P(improvement) below it
            (``pi``), skips a candidate.
        pessimism: a skipped candidate is told ``mean - pessimism x std`` (capped below the best).
        min_points: real evaluations needed before an online model is first trained.
        retrain_every: retrain after this many new real evaluations (0: never retrain a pre-trained model;
            an online model always retrains).
        max_skips: consecutive skips after which the next candidate is simulated anyway.
        kind: model kind of an online model (``ensemble`` or ``knn``).
        skips: how a skip is told to the inner agent (:class:`SkipAccounting`; default ``EVALUATION``).
        lowfi: an online model's features include a low-fidelity flight of each test (one ~0.1 s flight per
            candidate screened; see :mod:`surrogates.lowfi`).
        first_runs: racing: a candidate that passes the screen first flies only this many of its runs, and the
            rest only if the fitness of those runs falls short of the incumbent's first runs by no more than
            ``race_margin`` (0: off; must be below the env's runs). A tuple races in stages: after each of its
            run counts (increasing, e.g. ``(1, 2, 3, 4)``) the candidate is compared again and dropped at the
            first stage it falls behind; later stages fly only the runs not flown yet.
        race_margin: racing's margin (fitness units, every stage); None calibrates one per stage like the
            ``lowfi`` margin, on the model's training stores and the episode's evaluations, each stage at an equal
            share of ``miss_rate`` (so the stages together miss about ``miss_rate`` of the improvements).
        drop_ties: racing also drops a candidate whose first runs score exactly as the incumbent's (told just
            below the best): with common random numbers the mutation left those flights unchanged. None (default):
            on when the env flies common noise and no real improvement in the model's training stores tied its
            incumbent (:func:`~surrogates.racing.tie_improvements`; checked again at each retrain).
        verify_stop: when the inner agent stops with budget left, start it again from the best test with
            screening and racing off, so that a stop the skips may have caused is checked by simulation (tests
            already simulated are memo hits and cost nothing).
    """

    rule: str = "auto"
    margin: float | None = None
    miss_rate: float = 0.02
    threshold: float = 0.01
    pessimism: float = 1.0
    min_points: int = 10
    retrain_every: int = 5
    max_skips: int = 20
    kind: str = "ensemble"
    skips: SkipAccounting = SkipAccounting.EVALUATION
    lowfi: bool = True
    first_runs: int | tuple[int, ...] = 0
    race_margin: float | None = None
    drop_ties: bool | None = None
    verify_stop: bool = False

    def __post_init__(self):
        if isinstance(self.first_runs, (list, tuple)):
            object.__setattr__(self, "first_runs", tuple(int(k) for k in self.first_runs))  # hashable, frozen
        if self.rule not in RULES:
            raise ValueError(f"prescreen rule: expected one of {', '.join(RULES)}, got {self.rule!r}")
        if not 0.0 <= self.miss_rate < 1.0:
            raise ValueError(f"prescreen miss_rate: expected a share in [0, 1), got {self.miss_rate!r}")
        try:
            object.__setattr__(self, "skips", SkipAccounting(self.skips))
        except ValueError:
            raise ValueError(f"prescreen skips: expected one of {[s.value for s in SkipAccounting]}, got "
                             f"{self.skips!r}") from None
        stages = self.race_stages
        if any(k < 1 for k in stages) or any(b <= a for a, b in zip(stages, stages[1:])):
            raise ValueError(f"prescreen first_runs: expected 0 (off), a number of runs or increasing numbers of "
                             f"runs, got {self.first_runs!r}")

    @property
    def race_stages(self) -> tuple[int, ...]:
        """The run counts after which racing compares a candidate with the incumbent (empty: racing off)."""
        if isinstance(self.first_runs, tuple):  # __post_init__ turns any sequence into a tuple
            return self.first_runs
        return (int(self.first_runs),) if self.first_runs else ()


__all__ = ["RULES", "PrescreenConfig", "SkipAccounting"]
