"""Notebook 05's scorecard: its inputs, and the texts its rows and captions state.

The simulated experiment's layout and declared inputs (:func:`experiment_genes`,
:func:`experiment_inputs`); how a caption states a layout, a mapping or a difference
(:func:`layout_text`, :data:`MAPPING_TEXT`, :func:`difference_text`); the texts of Table 1's
check, of Fig. 10's range under every reading of its orders and of Section 3's recommended
ranges (:func:`table1_consistency_texts`, :func:`fig10_readings`, :func:`ranges_statement`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..printed import half_unit

__all__ = ["experiment_genes", "layout_text", "experiment_inputs", "MAPPING_TEXT",
           "difference_text", "table1_consistency_texts", "fig10_readings", "ranges_statement"]


def experiment_genes(facts):
    """The layout of the paper's lathe experiment, as printed: genes ``(phi_1, phi_2, phi_3, a_3)``.

    From ``data/papers/yang2021_facts.csv`` (Table 1's k = 20 row, which Section 3 says the
    experiment used); ``a_1, a_2`` are left to Eq. 15.

    Parameters
    ----------
    facts : pandas.Series
        The published facts indexed by quantity (strings): ``experiment_angles`` (three angles,
        rad, separated by spaces) and ``experiment_a3``.

    Returns
    -------
    numpy.ndarray
        ``(4,)``: the three angles (rad) and ``a_3``.

    Raises
    ------
    ValueError
        ``experiment_angles`` does not hold three angles.
    """
    phi = [float(v) for v in str(facts["experiment_angles"]).split()]
    if len(phi) != 3:
        raise ValueError(f"yang2021_facts.csv: experiment_angles needs 3 angles, got {phi}")
    return np.array([*phi, float(facts["experiment_a3"])])


def layout_text(name: str, genes, positions, *, n_samples: int) -> str:
    """A probe layout as a caption states it: what it is, its genes and its sample positions.

    Parameters
    ----------
    name : str
        What the layout is (``"our best known optimum at k = 20"``).
    genes : array (4,)
        ``(phi_1, phi_2, phi_3, a_3)`` (rad, rad, rad, 1); ``a_1, a_2`` follow from Eq. 15.
    positions : sequence of int
        The sample positions the angles are rounded to, the first probe's (0) included.
    n_samples : int
        Samples per revolution.

    Returns
    -------
    str
        ``"<name> (φ = 0.522, 3.45, 5.47 rad, a3 = 1.39, a1 and a2 from Eq. 15, rounded to
        samples 0, 11, 70, 111 of 128)"``: three significant digits.
    """
    genes = np.asarray(genes, dtype=float)
    phi = ", ".join(f"{v:.3g}" for v in genes[:3])
    return (f"{name} (φ = {phi} rad, a3 = {genes[3]:.3g}, a1 and a2 from Eq. 15, rounded to "
            f"samples {', '.join(str(int(p)) for p in positions)} of {n_samples})")


def experiment_inputs(card, mandrel_roundness_um: float, calibration_um: float):
    """Declare the simulated lathe experiment's inputs on ``card``; ``(mandrel, simulation, sync)``.

    The mandrel is ``constructed`` when its roundness is the paper's calibration value (the
    value Table 2's shape errors, Fig. 21 and the abstract's deviation are compared with: the
    simulation then returns it by design), else ``simulated``; the noise, the asynchronous
    motion and the layouts are ``simulated``; the synchronous motion, the printed Section 1.3
    rotation error at every speed, is ``assumed``: it makes the separated curves coincide
    across speeds (Figs. 19-20) by design.

    Parameters
    ----------
    card : Card
        The scorecard (``mtaccuracy.compendium.reproduction.Card``, or anything with its
        ``constructed``, ``simulated`` and ``assumed`` methods).
    mandrel_roundness_um : float
        The simulated mandrel's minimum-zone roundness (um).
    calibration_um : float
        The paper's calibration value (um).

    Returns
    -------
    mandrel, simulation, sync : Input
        The inputs the card declared, for the rows' ``uses``.
    """
    at_calibration = abs(float(mandrel_roundness_um) - float(calibration_um)) <= 1e-12
    what = f"a mandrel of minimum-zone roundness {mandrel_roundness_um:g} um"
    if at_calibration:
        mandrel = card.constructed(
            "simulated mandrel at the calibration roundness",
            targets=["Table 2 (simulated)*", "Abstract (simulated)*", "Fig. 21 (simulated)*"],
            how=f"{what}, set to the paper's calibration value {calibration_um:g} um, the value "
                "Table 2, Fig. 21 and the abstract's deviation are compared with")
    else:
        mandrel = card.simulated("simulated mandrel", how=f"{what} (not the paper's calibration "
                                                          f"value {calibration_um:g} um)")
    simulation = card.simulated(
        "simulated lathe experiment",
        how="asynchronous motion, probe noise, acquisition, filter and layouts as assumed in "
            "Section 9; the paper publishes no measured data")
    same_sync = card.assumed(
        "synchronous motion the same at every speed",
        settles=["Fig. 19 (simulated)*", "Fig. 20 (simulated)*"],
        how="the printed Section 1.3 rotation error is the synchronous motion at every speed and "
            "the mandrel is one object, so the separated mean curves of the four speeds agree by "
            "design, up to the noise")
    return mandrel, simulation, same_sync


#: How a caption states each mapping of :data:`~mtaccuracy.spindle.MAPPINGS` (the scalar
#: rotation error to the motion the probes see).
MAPPING_TEXT = {"radial": "purely radial, δx = δ cos θ, δy = δ sin θ (the inverse of Eq. 9)",
                "radial_reversed": "radial along the direction turning with the workpiece, "
                                   "δx = δ cos θ, δy = −δ sin θ",
                "x_only": "along a fixed direction, the first probe's: δx = δ, δy = 0"}


def difference_text(difference: float, scale: float, *, roundoff: float) -> str:
    """How a caption states the largest difference between two curves: round-off, or its size.

    Parameters
    ----------
    difference : float
        The largest absolute difference (um).
    scale : float
        The largest absolute value of the curves compared (um).
    roundoff : float
        The fraction of ``scale`` below which a difference is round-off.

    Returns
    -------
    str
        ``"zero"``; ``"of order 1e-14 µm: round-off"`` (the power of ten at or below the
        difference) when it is below ``roundoff * scale``; else ``"up to 0.0123 µm"``.
    """
    d = abs(float(difference))
    if d == 0:
        return "zero"
    if d < roundoff * abs(float(scale)):
        return f"of order {10.0 ** np.floor(np.log10(d)):.0e} µm: round-off"
    return f"up to {d:.3g} µm"


def table1_consistency_texts(row, printed_row):
    """The scorecard texts of one Table 1 row's check: do the printed parameters give its H?

    Scored as a number: the printed H against Eq. 20 at the printed parameters as printed
    (``H_as_printed``), and ``close`` only where a conclusion holds once corrected: the printed
    angles and a3 give the printed H with Eq. 15's weights, which are the printed ones (a1
    perhaps up to its sign).

    Parameters
    ----------
    row : pandas.Series
        One row of :func:`table1_consistency`.
    printed_row : pandas.Series
        The same row of the published Table 1 (strings): ``H``, ``phi1_rad``..``phi3_rad``,
        ``a1``..``a3``.

    Returns
    -------
    ours : float
        Eq. 20 at the printed angles with the printed weights.
    conclusion : str
        The conclusion that may hold after a correction, in words.
    holds : bool
        The printed H is possible for the printed weights, and the printed H and weights lie in
        the ranges of Eqs. 15 and 20 within the printed rounding (a1 perhaps up to its sign).
    note : str
        The printed parameters, what Eq. 15's weights give, and the weights-only bound.
    """
    r, pr = row, printed_row
    printed = (f"printed phi = ({pr.phi1_rad}, {pr.phi2_rad}, {pr.phi3_rad}), "
               f"a = (1, {pr.a1}, {pr.a2}, {pr.a3})")
    bound = (f"weights-only bound (1 + sum a^2) / (1 + sum |a|)^2 over every weight that "
             f"rounds to the printed ones: H >= {r.H_weights_only_bound:.4f} for every "
             "probe-angle choice")
    conclusion = ("the printed angles and a3 give the printed H with Eq. 15's weights, which "
                  "are the printed ones")
    ok = bool(r.H_possible_for_the_weights) and bool(r.H_consistent) \
        and (bool(r.a1_consistent) or bool(r.abs_a1_consistent)) and bool(r.a2_consistent)
    if ok and not r.a1_consistent:
        conclusion += " once the sign of a1 is restored"
    if not r.H_possible_for_the_weights:
        said = f"impossible: the printed weights force H >= {r.H_weights_only_bound:.3f}"
    else:
        said = (f"Eq. 15's weights at the printed angles and a3 give H "
                f"{r.H_min_within_rounding:.3f}..{r.H_max_within_rounding:.3f} within the "
                f"rounding, a1 {r.eq15_a1_min:.3f}..{r.eq15_a1_max:.3f}, a2 "
                f"{r.eq15_a2_min:.3f}..{r.eq15_a2_max:.3f}")
    note = f"Eq. 20 with the {printed}; {said}; {bound}"
    return float(r.H_as_printed), conclusion, ok, note


def fig10_readings(sweep, k_lost, h_lost, *, k_tab: int):
    """The range of the optimum H over Fig. 10's orders, under every reading of those orders.

    The paper does not say which orders Fig. 10 covers: Table 1 ("some orders") takes k = 10 to
    80 from it, and its lost second part k = 240 to 360.  Each reading starts at one order from
    the sweep's smallest to ``k_tab`` (Table 1's smallest) and takes every order of the sweep from
    there and the lost ones.

    Parameters
    ----------
    sweep : pandas.DataFrame
        The optimum per harmonic order: ``k``, ``H_best_known``.
    k_lost : array of int
        The orders of Table 1's second part.
    h_lost : array, same length as ``k_lost``
        The best known H at those orders.
    k_tab : int
        The smallest order Table 1 tabulates: the last reading starts there.

    Returns
    -------
    pandas.DataFrame
        One row per reading: ``k_from``, ``low`` and ``high`` (the smallest and largest best
        known H over the reading's orders) and ``k_low``, ``k_high`` (where they are).
    """
    k_all = np.r_[np.asarray(sweep.k, dtype=int), np.asarray(k_lost, dtype=int)]
    h_all = np.r_[np.asarray(sweep.H_best_known, dtype=float), np.asarray(h_lost, dtype=float)]
    rows = []
    for k0 in sorted(int(k) for k in sweep.k if k <= k_tab):
        sel = k_all >= k0
        k, h = k_all[sel], h_all[sel]
        rows.append(dict(k_from=k0, low=h.min(), high=h.max(), k_low=int(k[np.argmin(h)]),
                         k_high=int(k[np.argmax(h)])))
    return pd.DataFrame(rows)


def ranges_statement(sweep, k_lost, h_lost, *, band_text: str, full_circle=None):
    """Section 3's recommended ranges against Fig. 10's band, at every order the claim covers.

    "Each probe has a suitable range for every harmonic order": the best known H in the ranges at
    every order of the sweep (from k = 2, the lowest order the method separates) and at the orders
    of Table 1's lost second part, against the printed upper edge of Fig. 10's band plus half a
    unit of its last digit, the paper's own statement of what its optimisation reaches (any
    stricter standard fails at more orders).

    Parameters
    ----------
    sweep : pandas.DataFrame
        The optimum per harmonic order: ``k``, ``H_best_known``.
    k_lost : array of int
        The orders of Table 1's second part, whose values are lost in the text.
    h_lost : array, same length as ``k_lost``
        The best known H at those orders.
    band_text : str
        The upper edge of Fig. 10's band, as printed.
    full_circle : mapping of int to float, optional
        The best known H on the full circle at some orders: the note gives it at the orders
        above the band.

    Returns
    -------
    ours : str
        At how many orders the best known H lies within the band, and where it does not.
    holds : bool
        Within the band at every order.
    note : str
        The orders above the band with their H (and the full circle's), how close to 1/4
        elsewhere, and what is left untested.
    """
    top = float(band_text) + half_unit(band_text)
    k_all = np.r_[np.asarray(sweep.k, dtype=int), np.asarray(k_lost, dtype=int)]
    h_all = np.r_[np.asarray(sweep.H_best_known, dtype=float), np.asarray(h_lost, dtype=float)]
    bad = h_all > top
    full = dict(full_circle or {})
    ours = (f"best known H in the ranges within Fig. 10's band (<= {band_text}) at "
            f"{int((~bad).sum())} of {len(k_all)} orders k = {int(sweep.k.min())}.."
            f"{int(sweep.k.max())} and {' '.join(map(str, k_lost))}"
            + (f"; above it at k = {' '.join(map(str, k_all[bad]))}" if bad.any() else ""))
    above = "; ".join(f"k = {k}: {h:.3f}" + (f" (full circle {full[k]:.3f})" if k in full else "")
                      for k, h in zip(k_all[bad], h_all[bad], strict=True))
    note = ((f"above the band: {above}; " if bad.any() else "")
            + (f"elsewhere within {100 * (h_all[~bad] / 0.25 - 1).max():.1f} % of 1/4; "
               if (~bad).any() else "")
            + f"orders {int(sweep.k.max()) + 1}..{min(k_lost) - 1} not computed; Table 1's "
            f"second part (k = {min(k_lost)}..{max(k_lost)}) is lost in the text, so its H are "
            "ours only; the ranges exclude the pair layouts that reach 1/4 at even k on the full "
            "circle; every Table 1 layout lies inside them")
    return ours, bool(not bad.any()), note
