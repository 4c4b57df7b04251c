"""The numbers the captions state, as text: every one computed by the run.

:func:`data_fields` (the data figures), :func:`model_fields` (the model figures),
:func:`loeo_fields` (leave one experiment out) and :func:`pooled_fields` (the baselines);
:func:`.figures.caption` fills them into :data:`.figures.FIGURES`.
"""

from __future__ import annotations

import numpy as np

from ... import thermal
from .checks import ERROR, METHODS

__all__ = ["data_fields", "model_fields", "loeo_fields", "pooled_fields"]


_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
          "eleven", "twelve")


def _counted(n: int, noun: str) -> str:
    """``four experiments``, ``one sensor``, ``15 positions``."""
    return f"{_WORDS[n] if 0 <= n < len(_WORDS) else n} {noun}{'' if n == 1 else 's'}"


def _listed(items) -> str:
    """``1 to 3`` (three or more consecutive integers), else ``1, 3 and 5``."""
    items = [str(v) for v in items]
    as_int = [int(v) for v in items if v.lstrip("-").isdigit()]
    if len(items) >= 3 and len(as_int) == len(items) and as_int == list(
            range(as_int[0], as_int[0] + len(as_int))):
        return f"{items[0]} to {items[-1]}"
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def _um(v: float, digits: int = 1) -> str:
    """A signed number with a typographic minus (``−6.0``)."""
    return f"{v + 0.0:.{digits}f}".replace("-", "−")


def _extreme(d) -> tuple[float, float]:
    """The error of largest magnitude of ``d`` and its position (mm)."""
    i, j = np.unravel_index(np.abs(d.errors).argmax(), d.errors.shape)
    return float(d.errors[i, j]), float(d.positions_mm[j])


def _farthest(data, others, test) -> str:
    """The sentence of Fig. 9's caption on the experiments that drift furthest."""
    ext = {e: _extreme(data.subset(e)) for e in others}
    far = max(others, key=lambda e: abs(ext[e][0]))
    v, p = ext[far]
    predicted = ", the one predicted in Figs. 11 to 17,"
    if far == test:
        return f"Experiment {far}{predicted} drifts furthest ({_um(v)} µm at {p:g} mm)."
    out = f"Experiment {far} drifts furthest ({_um(v)} µm at {p:g} mm)"
    if test in ext:
        out += f"; experiment {test}{predicted} reaches {_um(ext[test][0])} µm"
    return out + "."


def data_fields(data, *, train, test, air) -> dict[str, str]:
    """The numbers the captions of the data figures (Figs. 3, 5-10, 12) state, as text.

    Parameters
    ----------
    data : ThermalData
        The measurements.
    train : list of int
        The training experiments.
    test : int
        The test experiment.
    air : str or None
        The ambient sensor, if the data have it.

    Returns
    -------
    dict of str
        Fields of :data:`FIGURES`' texts: the experiments, measurements, times, feeds,
        positions and sensors; the first experiment's largest error, drift and zeroed spread
        (Figs. 5-8); the experiments that drift furthest (Fig. 9); the warmest and steadiest
        sensors (Fig. 10); the split.
    """
    exps = [int(e) for e in data.experiments]
    first, others = exps[0], exps[1:]
    per = data.index.groupby("experiment").size()
    d = data.subset(first)
    t, pos = d.index.time_min.to_numpy(float), data.positions_mm
    drift = np.ptp(d.errors, axis=0)
    v, p = _extreme(d)
    temps = d.temperatures
    feed = {e: f"{data.feeds[e]:g}" for e in exps if e in data.feeds}
    feeds = [float(data.feeds[e]) for e in exps if e in data.feeds]
    return {
        "air": air or "",
        "experiments": _counted(len(exps), "warm-up experiment"),
        "measurements": (_counted(int(per.iloc[0]), "measurement") if per.nunique() == 1
                         else f"{per.min()} to {per.max()} measurements"),
        "times": f"{data.index.time_min.min():g} to {data.index.time_min.max():g} min",
        "feeds": f", feeds {min(feeds):g} to {max(feeds):g} mm/min" if feeds else "",
        "first": str(first),
        "first_feed": f" ({feed[first]} mm/min)" if first in feed else "",
        "positions": f"{_counted(len(pos), 'target position')} {pos[0]:g} to {pos[-1]:g} mm",
        "pos_first": f"{pos[0]:g}", "pos_last": f"{pos[-1]:g}",
        "first_times": f"{t[0]:g} to {t[-1]:g} min", "duration": f"{t[-1] - t[0]:g}",
        "first_extreme": f"{_um(v)} µm at {p:g} mm",
        "drift": f"{drift.min():.1f} to {drift.max():.1f} µm",
        "zeroed": f"{np.ptp(d.errors - d.errors[:, [0]], axis=0).max():.1f}",
        "others": _listed(others),
        "others_feeds": (f" ({', '.join(feed[e] for e in others)} mm/min)"
                         if all(e in feed for e in others) else ""),
        "farthest": _farthest(data, others, test),
        "sensors": _counted(len(data.sensors), "sensor"),
        "warmest": _listed(temps.mean().sort_values(ascending=False, kind="stable").index[:3]),
        "steadiest": _listed((temps.max() - temps.min()).sort_values(kind="stable").index[:3]),
        "train": _listed(train), "test": str(test),
    }


def _points(sensors, paper: bool) -> str:
    return (f"the paper's sensitive points {_listed(sensors)}" if paper else
            f"the sensitive points {_listed(sensors)}, selected on the training experiments")


def model_fields(split, paper_inputs: dict, metrics=None) -> dict[str, str]:
    """The numbers the captions of the model figures (Figs. 11, 14-17) state, as text.

    Parameters
    ----------
    split : SplitResult
        :func:`mtaccuracy.thermal.evaluate_split` on the notebook's split.
    paper_inputs : dict
        :func:`published_inputs`, to say whether the models used the paper's points.
    metrics : pandas.DataFrame, optional
        :func:`published_metrics`: given (on the paper's reconstruction), each model's
        numbers are followed by the paper's, e.g. `` (Table 7: 0.6 µm)``.

    Returns
    -------
    dict of str
        ``points``, ``k_points``, ``b_points``, ``kernels``, and for ``pbp``, ``mlr``,
        ``svr``: ``<m>_lo``, ``<m>_hi`` (the residual's range, µm), ``<m>_rmse``, ``<m>_k_max``,
        ``<m>_b_max`` and the paper's ``<m>_paper``, ``<m>_kb_paper`` (empty without
        ``metrics``).
    """
    t = split.table.set_index(["method", "target"])
    kinds = thermal.svr_hyperparameters(split.models["decoupled_svr"]).kernel.tolist()
    names = [{"rbf": "an RBF kernel"}.get(k, f"a {k} kernel") for k in kinds]
    paper = {k: split.inputs[k] == paper_inputs[k] for k in ("point", "k", "b")}
    out = {"points": _points(split.inputs["point"], paper["point"]),
           "k_points": _listed(split.inputs["k"]), "b_points": _listed(split.inputs["b"]),
           "kb_how": ("the paper's sensitive points" if paper["k"] and paper["b"]
                      else "sensitive points selected on the training experiments"),
           "kernels": (f"{kinds[0]} kernels".replace("rbf", "RBF") if len(set(kinds)) == 1
                       else f"{names[0]} for k and {names[1]} for b")}
    p = metrics.set_index(["method", "target"]) if metrics is not None else None
    for short, m in zip(("pbp", "mlr", "svr"), METHODS, strict=True):
        resid = split.measured - split.predictions[m]
        out |= {f"{short}_lo": _um(resid.min()), f"{short}_hi": _um(resid.max()),
                f"{short}_rmse": f"{t.loc[(m, ERROR), 'rmse']:.2f}",
                f"{short}_paper": "", f"{short}_kb_paper": ""}
        if m != "point_by_point_mlr":
            out |= {f"{short}_k_max": f"{t.loc[(m, 'slope k'), 'max_residual']:.2f}",
                    f"{short}_b_max": f"{t.loc[(m, 'intercept b'), 'max_residual']:.2f}"}
        if p is not None and (m, ERROR) in p.index:
            row = p.loc[(m, ERROR)]
            out[f"{short}_paper"] = f" (Table {row.table}: {row.rmse} µm)"
            if (m, "slope k") in p.index and (m, "intercept b") in p.index:
                out[f"{short}_kb_paper"] = (f" (Table {row.table}: "
                                            f"{p.loc[(m, 'slope k'), 'max_residual']} µm/m and "
                                            f"{p.loc[(m, 'intercept b'), 'max_residual']} µm)")
    return out


_CHOICES = {"published": "the paper's points", "selected": "re-selected points"}


def loeo_fields(wide, choices) -> dict[str, str]:
    """The numbers the caption of the leave-one-experiment-out figure states, as text.

    Parameters
    ----------
    wide : pandas.DataFrame
        Held-out RMSE by (inputs, held_out) and method, with the columns ``decoupled MLR beats
        point-by-point`` and ``decoupled SVR beats point-by-point``.
    choices : list of str
        The sensor choices run: ``published`` and/or ``selected``.

    Returns
    -------
    dict of str
        ``panels`` (what each panel shows) and ``wins`` (in how many splits each decoupled
        model beats point-by-point, per choice).
    """
    panels = {"published": "with the paper's sensitive points",
              "selected": "with points re-selected by the paper's own procedure on each "
                          "training set"}
    where = [" (left)", " (right)"] if len(choices) == 2 else [""]
    wins = []
    for c in choices:
        w = wide.loc[c]
        wins.append(f"with {_CHOICES[c]}, decoupled MLR beats point-by-point in "
                    f"{int(w['decoupled MLR beats point-by-point'].sum())} of {len(w)} splits "
                    f"and decoupled SVR in {int(w['decoupled SVR beats point-by-point'].sum())}")
    text = "; ".join(wins)
    return {"panels": " and ".join(panels[c] + s for c, s in zip(choices, where, strict=True)),
            "wins": text[0].upper() + text[1:] + "."}


def pooled_fields(pooled, n_sensors: int) -> dict[str, str]:
    """The numbers the caption of the baselines figure states, as text.

    Parameters
    ----------
    pooled : pandas.DataFrame
        The pooled rows of :func:`mtaccuracy.thermal.selection_vs_baselines`, indexed by model.
    n_sensors : int
        Sensors of the data (the ridge baseline uses all).

    Returns
    -------
    dict of str
        ``all_sensors``, ``with_points`` (the sensor choices shown) and ``pooled`` (every
        model's pooled RMSE, µm).
    """
    r = pooled.rmse
    label = {"point_by_point_mlr": "point-by-point", "decoupled_mlr": "decoupled MLR",
             "decoupled_svr": "decoupled SVR"}
    parts = [f"uncompensated {r['uncompensated']:.2f}", f"ridge {r['ridge_all_sensors']:.2f}"]
    choices = [c for c in _CHOICES if f"decoupled_mlr ({c})" in r.index]
    for c in choices:
        parts.append(f"with {_CHOICES[c]}: " + ", ".join(
            f"{label[m]} {r[f'{m} ({c})']:.2f}" for m in METHODS if f"{m} ({c})" in r.index))
    return {"all_sensors": _counted(n_sensors, "sensor"), "pooled": "; ".join(parts),
            "with_points": " and ".join(f"with {_CHOICES[c]}" for c in choices)}
