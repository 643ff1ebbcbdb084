"""The track's score of a set of flights: the rank key ``mech_rate``, the diagnostics flights alone give, the mean
over evaluations and the noise band between two entries.

Sources: the track's README, section "Scoring" (the breadth formula, the table of eight diagnostics, the noise band)
and section "How a submission is evaluated" (twenty scenarios, each flown three times; a flight without a usable
record is invalid for that repeat), restated in ``../shared/TRACK2027.md`` section 4.

What the sources leave open, and how it is settled here:

- ``r``, "the share of that band's flights that reach the mechanism": the band's flights are those that count
  (valid and admissible), as ``crash`` says of its flights and as the board counts 56 flights for the entry whose
  validity is 0.933 (56 of 60).
- ``severity`` is a mean "over flights": it is given only when every counted flight's minimum true clearance is
  known (None otherwise); ``clip`` bounds to [0, 1].
- ``output_div`` ("spread of the flown paths") is defined no further, so it is not computed; the flown path is
  kept on each flight for when it is. ``input_div`` is :func:`.measures.input_div`; ``mech_rarity`` and
  ``novelty`` need the sample tools' flights, which are not published.

Example:
    >>> from surrealist_gym.forest.records import Mechanism, Outcome, RoutePhase, StruckObject, VehiclePart
    >>> strike = Mechanism(StruckObject.POLE, VehiclePart.ROTOR, RoutePhase.TURN)
    >>> flights = [FlightOutcome(3.0, Outcome.COLLISION, True, (strike,)), FlightOutcome(6.0, Outcome.GOAL, True, ())]
    >>> round(mech_rate(flights), 4)  # tight: one cell at r = 1 scores 1 of 12; wide: nothing
    0.0417
"""
from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field
from typing import Iterable, Sequence

from ..errors import FrozenDict, SurrealistError
from .measures import Band
from .records import ManifestRecord, Mechanism, Outcome, RoutePhase, StruckObject, VehiclePart
from .scenario import is_number, shown
from .space import TIGHT_BAND_CORRIDOR_M

#: The 12 mechanism cells: object x vehicle part x route phase (README "What counts as a failure").
CELLS = tuple(Mechanism(o, p, h) for o in StruckObject for p in VehiclePart for h in (RoutePhase.LEG, RoutePhase.TURN))
#: The six (object, vehicle part) pairs ``mechanism`` counts (README "Scoring", its table).
PAIRS = tuple((o, p) for o in StruckObject for p in VehiclePart)
SATURATION_SHARE = 0.10  # a cell's credit is min(1, sqrt(r / 0.10)) (README "Scoring")
SEVERITY_CLEARANCE_M = 1.5  # [m] severity is clip(1 - m / 1.5) (README "Scoring", its table)
NOISE_CONFIDENCE = 0.95  # the noise band is the half-width of the 95% Welch t interval (README "Scoring")
BOARD_NOISE_BAND = 0.146  # the band the board uses, the widest between the sample tools (README "Scoring")

Point3 = tuple[float, float, float]


class ScoringError(SurrealistError):
    """A flight or a set of evaluations that cannot be scored: one line naming where it came from and the field."""


@dataclass(frozen=True, slots=True)
class FlightOutcome:
    """One flight as the track scores it.

    Attributes:
        corridor: its scenario's corridor [m], which puts the flight in a band.
        outcome: how the flight ended (only a collision is a failure).
        counts: whether it counts: a usable record, and admissible.
        mechanisms: the cells its strike reached; empty without a collision; None for a collision whose contact
            record could not be read (a crash with no mechanism).
        min_clearance: its minimum true clearance [m], or None if not known.
        path: the flown path, (x, y, z) [m] points, or None if not known.
        source: where the flight came from, for messages (a file, a scenario and repeat).
    """

    corridor: float
    outcome: Outcome
    counts: bool
    mechanisms: tuple[Mechanism, ...] | None
    min_clearance: float | None = None
    path: tuple[Point3, ...] | None = None
    source: str = field(default="flight", compare=False)

    def __post_init__(self):
        def bad(name: str, expected: str) -> ScoringError:
            return ScoringError(f"{self.source}: {name}: expected {expected}, got {shown(getattr(self, name))}")

        if not is_number(self.corridor) or self.corridor <= 0:
            raise bad("corridor", "a finite number above 0")
        if not isinstance(self.outcome, Outcome):
            raise bad("outcome", f"one of {[o.value for o in Outcome]}")
        if not isinstance(self.counts, bool):
            raise bad("counts", "true or false")
        if self.mechanisms is None:
            if self.outcome is not Outcome.COLLISION:
                raise bad("mechanisms", "a tuple of mechanisms (None is for a collision only)")
        elif not isinstance(self.mechanisms, tuple) or not all(isinstance(m, Mechanism) for m in self.mechanisms):
            raise bad("mechanisms", "a tuple of Mechanism or None")
        elif self.mechanisms and self.outcome is not Outcome.COLLISION:
            raise bad("mechanisms", f"none for a flight ending in {self.outcome.value}")
        if self.min_clearance is not None and not is_number(self.min_clearance):
            raise bad("min_clearance", "a finite number [m] or None")
        if self.path is not None and not (isinstance(self.path, tuple) and all(
                isinstance(p, tuple) and len(p) == 3 and all(is_number(v) for v in p) for p in self.path)):
            raise bad("path", "a tuple of (x, y, z) finite numbers or None")

    @property
    def band(self) -> Band:
        """Its corridor band: tight at and below 4.5 m, wide above (README "Scoring")."""
        return Band.TIGHT if self.corridor <= TIGHT_BAND_CORRIDOR_M else Band.WIDE

    @property
    def cells(self) -> frozenset[Mechanism]:
        """The cells it reached (a strike's contacts within 0.5 s may reach several; none if unread)."""
        return frozenset(self.mechanisms or ())


def flight_outcome(record: ManifestRecord, path: tuple[Point3, ...] | None = None) -> FlightOutcome:
    """The outcome of a train manifest's flight (TRACK2027.md section 6); it counts when valid and admissible, and
    the manifest gives no clearance."""
    return FlightOutcome(corridor=record.scenario.corridor, outcome=record.outcome, counts=record.counts,
                         mechanisms=record.mechanism, path=path,
                         source=f"manifest: {record.scenario.id} repeat {record.repeat}")


def manifest_outcomes(records: Iterable[ManifestRecord]) -> tuple[FlightOutcome, ...]:
    """:func:`flight_outcome` of each record, in order."""
    return tuple(flight_outcome(r) for r in records)


def counted(flights: Iterable[FlightOutcome]) -> list[FlightOutcome]:
    """The flights that count (usable and admissible)."""
    return [f for f in flights if f.counts]


def cell_counts(flights: Iterable[FlightOutcome]) -> FrozenDict:
    """How many of the counted flights reach each cell, by :class:`Mechanism` (cells reached by none left out)."""
    counts: dict[Mechanism, int] = {}
    for flight in counted(flights):
        for cell in flight.cells:
            counts[cell] = counts.get(cell, 0) + 1
    return FrozenDict(counts)


def band_breadth(flights: Sequence[FlightOutcome]) -> float:
    """One band's breadth: the mean over the 12 cells of min(1, sqrt(r / 0.10)), r the share of the counted flights
    reaching the cell; 0 for no counted flight (README "Scoring"; TRACK2027.md section 4). The caller picks the band."""
    flown = len(counted(flights))
    if not flown:
        return 0.0
    counts = cell_counts(flights)
    return sum(min(1.0, math.sqrt(counts.get(c, 0) / flown / SATURATION_SHARE)) for c in CELLS) / len(CELLS)


def mech_rate(flights: Sequence[FlightOutcome]) -> float:
    """The rank key, failure breadth: :func:`band_breadth` of the tight band and of the wide band, averaged; an
    empty band scores 0 (README "Scoring"; TRACK2027.md section 4)."""
    return statistics.mean(band_breadth([f for f in flights if f.band is b]) for b in Band)


def mechanism_share(flights: Sequence[FlightOutcome]) -> float:
    """``mechanism``: the share of the six (object, vehicle part) pairs the counted flights reach at least once
    (README "Scoring", its table)."""
    reached = {(c.struck, c.part) for c in cell_counts(flights)}
    return len(reached) / len(PAIRS)


def severity(flights: Sequence[FlightOutcome]) -> float | None:
    """``severity``: the mean of clip(1 - m / 1.5) to [0, 1] over the counted flights, m the minimum true clearance
    [m] (README "Scoring", its table); None without counted flights or if any lacks its clearance."""
    clearances = [f.min_clearance for f in counted(flights)]
    if not clearances or None in clearances:
        return None
    return statistics.mean(min(1.0, max(0.0, 1.0 - m / SEVERITY_CLEARANCE_M)) for m in clearances)


def crash(flights: Sequence[FlightOutcome]) -> float | None:
    """``crash``: the share of valid flights ending in a collision, an unread one included (README "Scoring");
    None without counted flights."""
    valid = counted(flights)
    return sum(f.outcome is Outcome.COLLISION for f in valid) / len(valid) if valid else None


def validity(flights: Sequence[FlightOutcome]) -> float | None:
    """``validity``: the share of the flights that gave a usable record and count (README "Scoring": of the twenty
    scenarios' flights, each flown three times); None for no flight."""
    return len(counted(flights)) / len(flights) if flights else None


@dataclass(frozen=True, slots=True)
class Evaluation:
    """One evaluation's score: the rank key and the diagnostics its flights give (README "Scoring").

    Attributes:
        mech_rate: the rank key.
        tight, wide: each band's breadth.
        mechanism, severity, crash, validity: the diagnostics (None where they cannot be computed).
        cells: how many counted flights reach each cell reached.
        flights: how many flights there were; counted: how many count.
    """

    mech_rate: float
    tight: float
    wide: float
    mechanism: float
    severity: float | None
    crash: float | None
    validity: float | None
    cells: FrozenDict
    flights: int
    counted: int


def evaluate(flights: Sequence[FlightOutcome]) -> Evaluation:
    """The score of one evaluation's flights (the track's: 20 scenarios flown 3 times each; any set here)."""
    flights = tuple(flights)
    tight = band_breadth([f for f in flights if f.band is Band.TIGHT])
    wide = band_breadth([f for f in flights if f.band is Band.WIDE])
    return Evaluation(mech_rate=(tight + wide) / 2, tight=tight, wide=wide, mechanism=mechanism_share(flights),
                      severity=severity(flights), crash=crash(flights), validity=validity(flights),
                      cells=cell_counts(flights), flights=len(flights), counted=len(counted(flights)))


@dataclass(frozen=True, slots=True)
class EntryScore:
    """An entry's score over its evaluations (the track runs three): the rank key is the mean of theirs, and each
    diagnostic the mean of theirs, None if any evaluation lacks it (README "Scoring"; the board's ``mechanism``
    figures are such means, e.g. 0.889 = 16/18)."""

    evaluations: tuple[Evaluation, ...]

    @property
    def breadths(self) -> tuple[float, ...]:
        """Each evaluation's rank key, in order."""
        return tuple(e.mech_rate for e in self.evaluations)

    @property
    def mech_rate(self) -> float:
        """The rank key: the mean breadth over the evaluations."""
        return statistics.mean(self.breadths)

    def mean(self, diagnostic: str) -> float | None:
        """The mean of one of :class:`Evaluation`'s diagnostics over the evaluations, None if any lacks it."""
        values = [getattr(e, diagnostic) for e in self.evaluations]
        return None if None in values else statistics.mean(values)


def score_entry(evaluations: Sequence[Sequence[FlightOutcome]], entry: str = "entry") -> EntryScore:
    """The score of an entry from its evaluations' flights; a :class:`ScoringError` naming ``entry`` for none."""
    if not evaluations:
        raise ScoringError(f"{entry}: evaluations: expected at least one evaluation's flights, got none")
    return EntryScore(tuple(evaluate(flights) for flights in evaluations))


def noise_band(breadths_a: Sequence[float], breadths_b: Sequence[float], confidence: float = NOISE_CONFIDENCE,
               where: str = "noise band") -> float:
    """The half-width of the Welch t interval (95 % by default) for the difference of two entries' mean breadths,
    from each entry's breadths per evaluation (README "Scoring"; TRACK2027.md section 4: 0.094-0.146 between the
    sample tools). 0 when neither entry's breadths vary; a :class:`ScoringError` naming ``where`` for fewer than two
    evaluations of an entry or a breadth that is not a finite number."""
    from scipy import stats  # scipy is needed here only

    for name, values in (("breadths_a", breadths_a), ("breadths_b", breadths_b)):
        if len(values) < 2 or not all(is_number(v) for v in values):
            raise ScoringError(f"{where}: {name}: expected at least two finite breadths, got {shown(values)}")
    terms = [statistics.variance(v) / len(v) for v in (breadths_a, breadths_b)]
    if sum(terms) == 0:
        return 0.0
    freedom = sum(terms) ** 2 / sum(t * t / (len(v) - 1) for t, v in zip(terms, (breadths_a, breadths_b)))
    return float(stats.t.ppf(0.5 + confidence / 2, freedom) * math.sqrt(sum(terms)))
