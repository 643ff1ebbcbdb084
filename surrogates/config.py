"""The settings of pre-screening (:class:`PrescreenConfig`), in three parts: how candidates are screened
(:class:`ScreenConfig`), raced (:class:`RaceConfig`) and how the model learns online (:class:`OnlineConfig`);
plus how skips are told to the agent and whether a stop is verified (:mod:`surrogates.prescreen`,
docs/surrogates.md). ``PrescreenConfig.of(**settings)`` takes the settings by name, without their part.

:data:`MEASURED_PRESCREEN` holds the settings whose savings docs/results.md reports, and
:func:`measured_prescreen` picks those for a model and a problem (what ``--surrogate MODEL`` alone runs).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from enum import Enum

from surrealist_gym.errors import FrozenDict

RULES = ("auto", "lowfi", "ei", "pi", "none")


class SkipAccounting(str, Enum):
    """How a skipped (or raced-out) candidate is told to the agent; the env's budget counts real simulations
    in every case."""

    MEMO = "memo"  #: as a free memo answer: the greedy does not charge it to its local budgets
    EVALUATION = "evaluation"  #: as an evaluation: the agent plans its own budgets as without screening
    BUDGET = "budget"  #: as an evaluation spent from the budget the agent sees, so it walks and stops as
    #: without screening, having simulated less; the real budget left is unused or goes to ``verify_stop``


@dataclass(frozen=True, slots=True)
class ScreenConfig:
    """Which candidates are skipped without a simulation.

    Attributes:
        rule: ``lowfi`` (low-fidelity shortfall), ``ei`` (expected improvement), ``pi`` (probability of
            improvement), ``none`` (skip nothing) or ``auto`` (``lowfi`` once a margin is known, else ``ei``).
        margin: ``lowfi``: skip when the low-fidelity fitness is below the incumbent's by more than this (fitness
            units); None calibrates it on the model's training data (see ``PrescreenConfig.miss_rate``).
        threshold: EI below ``threshold`` x std of the training targets (``ei``), or P(improvement) below it
            (``pi``), skips a candidate.
        pessimism: a candidate the model skips is told ``mean - pessimism x std`` (capped below the best).
        max_skips: consecutive skips after which the next candidate is simulated anyway.
    """

    rule: str = "auto"
    margin: float | None = None
    threshold: float = 0.01
    pessimism: float = 1.0
    max_skips: int = 20

    def __post_init__(self):
        if self.rule not in RULES:
            raise ValueError(f"prescreen rule: expected one of {', '.join(RULES)}, got {self.rule!r}")


@dataclass(frozen=True, slots=True)
class RaceConfig:
    """Racing: a candidate that passes the screen flies its runs in stages (:mod:`surrogates.racing`).

    Attributes:
        stages: the run counts after which the candidate is compared with the incumbent (``against``)
            (increasing, each below the env's runs, e.g. ``(1, 2, 3, 4)``; empty: racing off); it is dropped at the
            first stage it falls behind, and later stages fly only the runs not flown yet.
        margin: the shortfall that drops a candidate (fitness units, every stage); None calibrates one per stage
            like the ``lowfi`` margin, each stage at an equal share of ``PrescreenConfig.miss_rate``.
        drop_ties: also drop a candidate whose first runs score exactly as the incumbent's (told just below the
            best): with common random numbers the mutation left those flights unchanged. None: on when the env flies
            common noise and no real improvement in the model's training stores tied its incumbent.
        against: what the first runs race against: ``paired`` (the incumbent's same first runs, a paired comparison
            under common random numbers) or ``fitness`` (the incumbent's fitness over all its runs, the figure a
            candidate must beat; under each test's own noise its first runs share nothing with the candidate's).
            None: ``paired`` when the env flies common noise, else ``fitness``.
    """

    stages: tuple[int, ...] = ()
    margin: float | None = None
    drop_ties: bool | None = None
    against: str | None = None

    def __post_init__(self):
        stages = self.stages
        stages = (int(stages),) if isinstance(stages, int) and stages else tuple(int(k) for k in stages or ())
        object.__setattr__(self, "stages", stages)
        if any(k < 1 for k in stages) or any(b <= a for a, b in zip(stages, stages[1:])):
            raise ValueError(f"prescreen first_runs: expected 0 (off), a number of runs or increasing numbers of "
                             f"runs, got {self.stages!r}")
        if self.against not in (None, "paired", "fitness"):
            raise ValueError(f"prescreen race_against: expected paired or fitness, got {self.against!r}")


@dataclass(frozen=True, slots=True)
class OnlineConfig:
    """How the model learns from the search's own evaluations.

    Attributes:
        kind: model kind of an online model (``ensemble`` or ``knn``).
        min_points: real evaluations needed before an online model is first trained.
        retrain_every: retrain after this many new real evaluations (0: never retrain a pre-trained model; an
            online model always retrains).
        lowfi: an online model's features include a low-fidelity flight of each test (one ~0.1 s flight per
            candidate screened; :mod:`surrogates.lowfi`).
    """

    kind: str = "ensemble"
    min_points: int = 10
    retrain_every: int = 5
    lowfi: bool = True


@dataclass(frozen=True, slots=True)
class PrescreenConfig:
    """How candidates are screened, raced and the model retrained.

    Attributes:
        screen, race, online: the three parts (above).
        miss_rate: share of the past real improvements that a calibrated margin (screening's, or racing's over all
            its stages) may drop.
        skips: how a skip is told to the agent (:class:`SkipAccounting`).
        verify_stop: when the agent stops with budget left, start it again from the best test with screening
            and racing off, so that a stop the skips may have caused is checked by simulation (tests already
            simulated are memo hits and cost nothing).
    """

    screen: ScreenConfig = field(default_factory=ScreenConfig)
    race: RaceConfig = field(default_factory=RaceConfig)
    online: OnlineConfig = field(default_factory=OnlineConfig)
    miss_rate: float = 0.02
    skips: SkipAccounting = SkipAccounting.EVALUATION
    verify_stop: bool = False

    def __post_init__(self):
        if not 0.0 <= self.miss_rate < 1.0:
            raise ValueError(f"prescreen miss_rate: expected a share in [0, 1), got {self.miss_rate!r}")
        try:
            object.__setattr__(self, "skips", SkipAccounting(self.skips))
        except ValueError:
            raise ValueError(f"prescreen skips: expected one of {[s.value for s in SkipAccounting]}, got "
                             f"{self.skips!r}") from None

    @classmethod
    def of(cls, **settings) -> "PrescreenConfig":
        """A config from settings named without their part: ``rule``, ``margin``, ``threshold``, ``pessimism``,
        ``max_skips`` (screen); ``first_runs``, ``race_margin``, ``drop_ties``, ``race_against`` (race); ``kind``,
        ``min_points``, ``retrain_every``, ``lowfi`` (online); ``miss_rate``, ``skips``, ``verify_stop``."""
        renamed = {"first_runs": "stages", "race_margin": "margin", "race_against": "against"}
        parts = {"screen": ScreenConfig, "race": RaceConfig, "online": OnlineConfig}
        values: dict[str, dict] = {name: {} for name in parts}
        top = {}
        for key, value in settings.items():
            if key in ("miss_rate", "skips", "verify_stop"):
                top[key] = value
                continue
            part = "race" if key in renamed else next(
                (name for name, kind in parts.items() if key in {f.name for f in fields(kind)}), None)
            if part is None:
                raise TypeError(f"PrescreenConfig.of: unknown setting {key!r}")
            values[part][renamed.get(key, key)] = value
        return cls(**{name: kind(**values[name]) for name, kind in parts.items()}, **top)


# The pre-screening settings whose savings docs/results.md reports (PrescreenConfig.of's names), by the noise mode of
# the model's training stores (True: common random numbers) and the problem.
MEASURED_PRESCREEN = FrozenDict({
    (True, "generate"): FrozenDict(first_runs=(1, 2, 3, 4), skips=SkipAccounting.BUDGET, verify_stop=True),
    (True, "replicate"): FrozenDict(rule="none", first_runs=(1, 2, 3, 4), skips=SkipAccounting.BUDGET,
                                    verify_stop=True),
    (False, "replicate"): FrozenDict(rule="none", first_runs=(1, 2, 3, 4), skips=SkipAccounting.BUDGET,
                                     verify_stop=True),
    (False, "generate"): FrozenDict(first_runs=(1, 2, 3, 4), skips=SkipAccounting.BUDGET, verify_stop=True),
})


def measured_prescreen(common_noise: bool | None, problem: str, runs: int) -> FrozenDict:
    """The measured settings (:data:`MEASURED_PRESCREEN`) for a model trained in the noise mode ``common_noise`` and
    a search of ``problem`` (``replicate`` or ``generate``) flying ``runs`` runs per evaluation, by
    :meth:`PrescreenConfig.of`'s names; racing stages at or above ``runs`` are left out. Empty when none were
    measured (a model whose noise mode is unknown: None).

    Example:
        >>> measured_prescreen(False, "generate", runs=10)["first_runs"]
        (1, 2, 3, 4)
        >>> PrescreenConfig.of(**measured_prescreen(True, "replicate", runs=3)).race.stages
        (1, 2)
    """
    settings = MEASURED_PRESCREEN.get((common_noise, problem))
    if settings is None:
        return FrozenDict()
    return FrozenDict({**settings, "first_runs": tuple(k for k in settings["first_runs"] if k < runs)})


__all__ = ["MEASURED_PRESCREEN", "RULES", "OnlineConfig", "PrescreenConfig", "RaceConfig", "ScreenConfig",
           "SkipAccounting", "measured_prescreen"]
