"""Which UAV flies: the one place that decides.

A test, an optional UAV choice (a preset's name, a profile YAML or a :class:`~surrealist_gym.sim.profiles.UavProfile`)
and optional overrides go in; one :class:`~surrealist_gym.sim.config.SimConfig` comes out, with the reasons, which a
results folder records (:meth:`UavDecision.record`). Every command and env asks :func:`decide_uav`; the runner asks
:func:`flown_config` for the test's own ``uav.*`` settings of each test it flies.

==================================  ==========  ===================================  ===============================
``uav``                             ``flight``  ``test``                             UAV flown
==================================  ==========  ===================================  ===============================
a preset name, YAML or profile      any         any                                  that one
a UavDecision                       any         any                                  that one, decided already
None, ``config`` a full SimConfig   any         any                                  that SimConfig as given
None                                a log       any                                  the log's vehicle
None                                None        replicates a flight (reference log)  ``px4-vision-case0``
None                                None        any other test, or None              :data:`DEFAULT_UAV`
==================================  ==========  ===================================  ===============================

``config`` as a mapping of SimConfig fields (e.g. ``{"common_noise": True}``) is the overrides: the UAV's profile is
applied on top of them (the profile decides vehicle, planner, camera, noise and timing; the overrides everything
else). A test's ``uav.*`` params are applied last, test by test, when it flies.
"""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from ..errors import InvalidProfile
from .config import SimConfig
from .profiles import (
    PRESETS,
    SITL_IRIS,
    UavProfile,
    default_profile,
    load_profile,
    profile_for_flight,
    test_uav_settings,
    with_uav_settings,
)

__all__ = ["DEFAULT_UAV", "UAV_RECORD", "UavDecision", "decide_uav", "flown_config", "recorded_choice", "uav_settings",
           "write_record"]

#: The UAV a test flies when nothing names one and it replicates no flight: the PX4 SITL Iris with PX4-Avoidance that
#: Aerialist's simulators and the competition fly.
DEFAULT_UAV = SITL_IRIS.name
UAV_RECORD = "uav.json"  # what a results folder records of the UAV that flew and why


@dataclass(frozen=True, slots=True)
class UavDecision:
    """The UAV that flies and why.

    Attributes:
        config: the SimConfig every run flies with (before each test's own ``uav.*`` settings).
        profile: the profile flown, None when a full SimConfig was given as it is.
        reasons: one line each: which profile and why, which overrides, which test settings.
    """

    config: SimConfig
    profile: UavProfile | None
    reasons: tuple[str, ...]

    @property
    def name(self) -> str:
        """The profile's name ("custom SimConfig" for a SimConfig given as it is)."""
        return self.profile.name if self.profile is not None else "custom SimConfig"

    def record(self) -> dict:
        """What a results folder records of the decision (:meth:`write`)."""
        return {"uav": self.name, "reasons": list(self.reasons),
                "profile": self.profile.to_dict() if self.profile is not None else None}

    def write(self, folder) -> Path:
        """Record the decision in a results folder: ``uav.json``; its path."""
        return write_record(folder, {"": self})


def decide_uav(test=None, uav=None, *, flight=None, config: SimConfig | Mapping[str, Any] | None = None,
               option: str = "--uav") -> UavDecision:
    """The UAV that flies ``test`` (see the module's table). A choice that is no preset, or a YAML that cannot be
    read or is no valid profile, raises a one-line :class:`~surrealist_gym.errors.InvalidProfile` naming ``option``;
    a test whose ``uav.*`` settings the UAV cannot take raises :class:`~surrealist_gym.errors.InvalidTestCase`, both
    before anything flies."""
    if isinstance(uav, UavDecision):  # decided already (e.g. by an env that knows the log's vehicle)
        if test is not None:
            flown_config(uav.config, test)
        return uav
    if uav is None and isinstance(config, SimConfig):
        decision = UavDecision(config, None, ("a SimConfig given as it is",))
    else:
        if uav is not None:
            try:
                profile = load_profile(uav)
            except InvalidProfile as err:
                raise InvalidProfile(f"{option} {err}") from None
            why = f"{option} {profile.name}" + ("" if profile.name in PRESETS else " (a profile file)")
        elif flight is not None:
            profile = profile_for_flight(flight)
            why = f"the vehicle of the log {getattr(flight, 'path', '')}".rstrip()
        elif test is not None:
            profile = default_profile(test)
            why = ("the test replicates a real flight" if test.replicates_flight else "the default UAV")
        else:
            profile, why = SITL_IRIS, "the default UAV"
        reasons = (f"{profile.name}: {why}",)
        if isinstance(config, SimConfig):
            reasons += ("the profile applied to a SimConfig given",)
        elif config:
            reasons += ("overrides: " + ", ".join(f"{k}={v}" for k, v in sorted(dict(config).items())),)
        decision = UavDecision(profile.sim_config(SimConfig.coerce(config)), profile, reasons)
    if test is not None and (settings := uav_settings(test)):
        with_uav_settings(decision.config, settings)  # the test's uav.* settings, checked before anything flies
        decision = dataclasses.replace(decision, reasons=decision.reasons + (
            "the test's settings: " + ", ".join(f"uav.{k}={v:g}" for k, v in sorted(settings.items())),))
    return decision


def write_record(folder, decisions: Mapping[str, UavDecision]) -> Path:
    """Record in a results folder (``uav.json``) the UAV each test flew, by test: one record when all agree, else
    ``{"per_test": {test: record}}``; its path."""
    records = {name: decision.record() for name, decision in decisions.items()}
    distinct = {json.dumps(r, sort_keys=True) for r in records.values()}
    path = Path(folder) / UAV_RECORD
    doc = next(iter(records.values())) if len(distinct) == 1 else {"per_test": records}
    path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    return path


def uav_settings(test) -> dict[str, float]:
    """The UAV settings a test sets (its params ``uav.<setting>``), by setting."""
    return test_uav_settings(test)


def flown_config(config: SimConfig, test) -> SimConfig:
    """``config`` with the test's own ``uav.*`` params applied (what the runner flies each test with); one that the
    UAV cannot take raises :class:`~surrealist_gym.errors.InvalidTestCase` naming the param."""
    return with_uav_settings(config, uav_settings(test))


def recorded_choice(uav) -> str | None:
    """A UAV choice as a results folder records it for a resume: a preset's name as it is, a profile file by its
    absolute path (a resume from another folder reads the same file); checked now (InvalidProfile)."""
    if uav is None:
        return None
    decide_uav(uav=uav)
    return str(uav) if str(uav) in PRESETS else str(Path(str(uav)).resolve())
