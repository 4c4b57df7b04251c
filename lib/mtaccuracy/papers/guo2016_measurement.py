"""Notebook 03's measurement question: what Guo et al. 2016's XY circle test can confirm.

The paper validates its Spearman ranking with circle tests (Table 2: squareness 18.7 -> 5.3
µm/m after compensation).  In the paper's model every error is a constant; a circle reads how
the errors *vary* along the path, so the question needs errors that vary: the paper's chain
(:mod:`mtaccuracy.machines.vertical_xyfz`) with travels (:func:`circle_machine`), its error
motions as Legendre polynomials over them (:func:`mtaccuracy.measure.motions.motion_model`),
and the circle of :func:`mtaccuracy.measure.instruments.circle`.  :func:`circle_table` gives,
per error and Legendre term, what the circle sees structurally (any size, noise-free) and at
the paper's ranges with a stated noise (priors: ``MotionModel.prior_sd``), through
:func:`mtaccuracy.papers.visibility.visibility_table`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import three_axis_catalogue
from ..machines import vertical_xyfz
from ..machines.chain import ChainMachine
from ..measure.instruments import Measurement
from .figure import Caption
from .visibility import visibility_table

__all__ = ["circle_machine", "circle_table", "visible_peak",
           "CIRCLE_SEES"]

CIRCLE_SEES = Caption(
    "circle_xy_sees", "Beyond the paper",
    "What an XY circle (ballbar, radius {radius:g} mm, centre at the pose of Fig. 3, both "
    "directions, {n_points} readings each, noise {sigma:g} µm) sees of the 21 errors, each a "
    "Legendre polynomial of degree {degree} over an assumed travel of ±{travel:g} mm per axis "
    "(term [0]: the paper's constant error; [1]: its variation along the travel, for a "
    "positioning error the scale error). Structure: any size, noise-free; at the paper's ranges: "
    "priors from the uniform ranges of Fig. 3. Bold: the errors Fig. 3 ranks in the top 8 of a "
    "component. '-': a term the model drops (a straightness' slope is a squareness).")


def circle_machine(*, travel_mm: float, centre=(0.0, 0.0, 0.0)) -> ChainMachine:
    """The paper's XYFZ chain (Eqs. 1-10) with travels ``centre ± travel_mm`` on x, y and z.

    The paper gives no travels; a position-dependent error motion needs them
    (:func:`mtaccuracy.measure.motions.motion_model`: Legendre polynomials over each travel).
    Everything else is :class:`~mtaccuracy.machines.vertical_xyfz.VerticalXYFZ`'s.

    Parameters
    ----------
    travel_mm : float
        Half the travel of each linear axis, mm (> 0).
    centre : (3,) array_like
        The middle of the travels of x, y, z, mm (a test's default pose).

    Returns
    -------
    ChainMachine
        Topology ``w b X Y Z t``, the 21 errors of the three-axis catalogue, tool offsets
        ``D1, D2, D3``, travels ``(c - travel_mm, c + travel_mm)``.
    """
    travel = float(travel_mm)
    c = np.asarray(centre, dtype=float).reshape(-1)
    if not (np.isfinite(travel) and travel > 0) or c.shape != (3,) or not np.isfinite(c).all():
        raise ValueError(f"circle_machine: travel_mm must be a finite number > 0 (mm) and "
                         f"centre three finite numbers (mm), got {travel_mm!r}, {centre!r}")
    return ChainMachine(vertical_xyfz.TOPOLOGY, three_axis_catalogue(),
                        vertical_xyfz.placements(), name="vertical_xyfz", form="first_order",
                        tilt="first_order", tool_offsets=vertical_xyfz.TOOL_OFFSETS,
                        orientation="rotation_vector", axis_names=vertical_xyfz.AXES,
                        travels={a: (float(v) - travel, float(v) + travel)
                                 for a, v in zip(vertical_xyfz.AXES, c, strict=True)})


def circle_table(test: Measurement, *, prior_sd, shrink: float = 100.0) -> pd.DataFrame:
    """Per error and Legendre term: what the test sees, structurally and at the given priors.

    Parameters
    ----------
    test : Measurement
        The circle (any test of the model).
    prior_sd : (n_params,) array_like
        The parameters' prior standard deviations, mm or rad
        (:meth:`mtaccuracy.measure.motions.MotionModel.prior_sd`).
    shrink : float, default 100
        The factor of :func:`mtaccuracy.measure.identifiability.identifiability`.

    Returns
    -------
    pandas.DataFrame
        One row per chain error (catalogue order) and degree 0..``model.degree``: ``symbol``,
        ``degree``, ``parameter`` (the model's name, ``""`` for a dropped term),
        ``structure`` and ``structure_combination`` (any size, noise-free:
        :func:`~mtaccuracy.papers.visibility.structural_prior_sd`), ``at_ranges``
        and ``at_ranges_combination`` (at ``prior_sd``); a term the model drops, or that a
        constant error does not have, has status ``"n/a"`` and the reason as combination.
    """
    model = test.model
    d = test.design()
    s = np.asarray(prior_sd, dtype=float)
    if s.shape != (model.n_params,):
        raise ValueError(f"prior_sd must be ({model.n_params},), one per parameter of the "
                         f"model, got {s.shape}")
    structure, _ = visibility_table([d], symbols=model.names, prior_sd=None, shrink=shrink)
    ranges, _ = visibility_table([d], symbols=model.names, prior_sd=s, shrink=shrink)
    structure = structure[structure.test == d.name].set_index("symbol")
    ranges = ranges[ranges.test == d.name].set_index("symbol")
    rows = []
    for spec in model.machine.catalogue:
        for k in range(model.degree + 1):
            p = f"{spec.symbol}[{k}]" if model.degree > 0 else spec.symbol
            if p not in model.names:
                p = spec.symbol if k == 0 and spec.symbol in model.names else p
            if p in model.names:
                rows.append({"symbol": spec.symbol, "degree": k, "parameter": p,
                             "structure": structure.status[p],
                             "structure_combination": structure.combination[p],
                             "at_ranges": ranges.status[p],
                             "at_ranges_combination": ranges.combination[p]})
            else:                       # dropped, or a constant error (no term of degree k)
                why = model.dropped.get(p, "a constant error (location or squareness)")
                rows.append({"symbol": spec.symbol, "degree": k, "parameter": "",
                             "structure": "n/a", "structure_combination": why,
                             "at_ranges": "n/a", "at_ranges_combination": why})
    return pd.DataFrame(rows)


def visible_peak(test: Measurement, *, parameters) -> pd.Series:
    """The largest change of a reading per unit of each parameter, beyond the nuisances.

    The part of the parameter's effect the test's set-up cannot absorb: its column of readings
    less its least-squares fit by the nuisances (for a circle: the centre and the bar length),
    largest in magnitude over the readings.  Times an error's size it is the largest reading
    that error alone can leave in the evaluated trace.

    Parameters
    ----------
    test : Measurement
        The test.
    parameters : sequence of str
        Names of the model's parameters (``test.model.names``).

    Returns
    -------
    pandas.Series
        Per parameter, reading units (um) per parameter unit (mm or rad), indexed by name.
    """
    d = test.design()
    unknown = [p for p in parameters if p not in d.errors]
    if unknown:
        raise ValueError(f"visible_peak: unknown parameters {unknown}; the model's are "
                         f"{', '.join(d.errors[:6])} ...")
    A = d.A[:, [d.errors.index(p) for p in parameters]]
    if d.N.shape[1]:
        A = A - d.N @ np.linalg.lstsq(d.N, A, rcond=None)[0]
    return pd.Series(np.abs(A).max(axis=0), index=pd.Index(list(parameters), name="parameter"),
                     name="peak")
