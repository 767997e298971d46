"""trueaxis: measure, separate, map and compensate geometric errors of machine tools and CMMs.

Units follow trueaxis' files: positions in mm, deviations in µm, angles in µrad.

Straightness separation (JPH0464003B2; Whitehouse 1976):

    >>> import trueaxis
    >>> sim = trueaxis.simulate_straightness(stations=200, offsets=[0, 10, 20])
    >>> r = trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"], method="three-point")
    >>> r["workpiece"]["value"]  # µm, residuals from the least-squares line

Error space and compensation of a virtual machine:

    >>> m = trueaxis.Machine.random(seed=3)
    >>> s = trueaxis.measure_space(m, spacing=100, probe_noise=0.05, verify=1000)
    >>> s["map"].compensate([[400.0, 300.0, 250.0]])  # commands (mm) that hit the wanted points
"""
from ._trueaxis import (
    Error,
    ErrorMap,
    Machine,
    analyze_layout,
    ballgauge,
    identify,
    fit,
    guideway,
    measure_space,
    moody,
    positioning,
    scan,
    separate,
    simulate_guideway,
    simulate_positioning,
    simulate_straightness,
    straightness,
    surface,
    verify_compensation,
    verify_lengths,
)

__all__ = [
    "Error",
    "ErrorMap",
    "Machine",
    "analyze_layout",
    "ballgauge",
    "identify",
    "fit",
    "guideway",
    "measure_space",
    "moody",
    "positioning",
    "scan",
    "separate",
    "simulate_guideway",
    "simulate_positioning",
    "simulate_straightness",
    "straightness",
    "surface",
    "verify_compensation",
    "verify_lengths",
]
__version__ = "0.1.0"
