"""trueaxis: measure, separate, map and compensate geometric errors of machine tools and CMMs.

Units follow trueaxis' files: positions in mm, deviations in µm, angles in µrad.

    >>> import trueaxis
    >>> sim = trueaxis.simulate_straightness(stations=200, offsets=[0, 10, 20])
    >>> r = trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"], method="three-point")
    >>> r["workpiece"]["value"]  # µm, residuals from the least-squares line
"""
from ._trueaxis import Error, analyze_layout, separate, simulate_straightness, straightness

__all__ = ["Error", "analyze_layout", "separate", "simulate_straightness", "straightness"]
__version__ = "0.1.0"
