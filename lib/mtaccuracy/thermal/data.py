"""The thermal measurements of one axis as the library holds them: :class:`ThermalData`.

Rows are measurements (experiment, measurement number, time); the temperatures of every sensor
and the positioning error at every target position of each.  :func:`rises_of` is the one
implementation of the temperature rises (Eq. 9's ``T - T0``).  Read and written by
:mod:`~mtaccuracy.thermal.io`.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

__all__ = ["ThermalData", "rises_of"]


@dataclass(frozen=True)
class ThermalData:
    """Measurements of one axis: rows are measurements (experiment, measurement number, time).

    Attributes
    ----------
    index : DataFrame (n, 3)
        ``experiment``, ``measurement``, ``time_min`` of each measurement.
    temperatures : DataFrame (n, S)
        One column per sensor (degC).
    errors : array (n, P)
        Positioning error (um) at each target position.
    positions_mm : array (P,)
        Target positions (mm).
    feeds : dict
        Experiment -> feed (mm/min), when ``experiments.csv`` gives it.
    source : str
        Where the data came from (a folder, or ``"reconstructed"``).
    dropped : dict
        Sensor name -> why :func:`~mtaccuracy.thermal.io.read_measurements` dropped it (a dead
        sensor, with the file and the value it reads); empty when none was.
    ignored_columns : dict
        Column name -> why :func:`~mtaccuracy.thermal.io.read_measurements` ignored it (the file
        holding it and what it is, e.g. ``"temperatures.csv: no unit, text"``); empty when none was.
    filled : dict
        Sensor name -> the short gaps of a lab export's logger that were interpolated (file,
        experiment, lines); empty when none were.
    """

    index: pd.DataFrame
    temperatures: pd.DataFrame
    errors: np.ndarray
    positions_mm: np.ndarray
    feeds: dict = field(default_factory=dict)
    source: str = ""
    dropped: dict = field(default_factory=dict)
    ignored_columns: dict = field(default_factory=dict)
    filled: dict = field(default_factory=dict)

    def __post_init__(self):
        n = len(self.index)
        if len(self.temperatures) != n or self.errors.shape != (n, len(self.positions_mm)):
            raise ValueError(f"inconsistent shapes: {n} measurements, temperatures "
                             f"{self.temperatures.shape}, errors {self.errors.shape}, "
                             f"{len(self.positions_mm)} positions")

    @property
    def sensors(self) -> list[str]:
        """list of str: the sensor names, in column order."""
        return list(self.temperatures.columns)

    @property
    def experiments(self) -> list[int]:
        """list of int: the experiment numbers, ascending."""
        return sorted(self.index.experiment.unique().tolist())

    @property
    def groups(self) -> np.ndarray:
        """The experiment of every row (for grouped cross-validation)."""
        return self.index.experiment.to_numpy()

    def subset(self, experiments) -> ThermalData:
        """The rows of the given experiments, in the stored order.

        Parameters
        ----------
        experiments : int or sequence of int
            Experiments kept (ValueError for an unknown one).

        Returns
        -------
        ThermalData
            Their measurements, with their feeds; positions and source unchanged.
        """
        experiments = [int(e) for e in np.atleast_1d(experiments)]
        unknown = sorted(set(experiments) - set(self.experiments))
        if unknown:
            raise ValueError(f"unknown experiment(s) {unknown}; the data have {self.experiments}")
        m = self.index.experiment.isin(experiments).to_numpy()
        return ThermalData(self.index[m].reset_index(drop=True),
                           self.temperatures[m].reset_index(drop=True), self.errors[m],
                           self.positions_mm,
                           {e: f for e, f in self.feeds.items() if e in experiments}, self.source,
                           dict(self.dropped), dict(self.ignored_columns), dict(self.filled))

    def rises(self) -> pd.DataFrame:
        """Temperatures relative to the first measurement of each experiment (Eq. 9's T - T0).

        Returns
        -------
        DataFrame (n, S)
            degC.
        """
        t = self.temperatures
        r = rises_of(t.to_numpy(dtype=float)[None], self.index.experiment.to_numpy())[0]
        return pd.DataFrame(r, index=t.index, columns=t.columns)

    def offsets_mm(self) -> np.ndarray:
        """Target positions shifted to start at 0 (185..445 mm -> 0..260 mm).

        Returns
        -------
        array (P,)
            mm.
        """
        return self.positions_mm - self.positions_mm[0]


def rises_of(temperatures: np.ndarray, experiments) -> np.ndarray:
    """Temperatures relative to the first measurement of each experiment, batched.

    The one implementation of :meth:`ThermalData.rises` (the inputs of Eqs. 8 and 9's b).

    Parameters
    ----------
    temperatures : array (R, n, S)
        R stacked datasets of n measurements of S sensors (degC).
    experiments : array (n,)
        Experiment of each measurement.

    Returns
    -------
    array (R, n, S)
        Rises (degC).
    """
    experiments = np.asarray(experiments)
    first = pd.Series(np.arange(len(experiments))).groupby(experiments).transform("first")
    t = np.asarray(temperatures, dtype=float)
    return t - t[:, first.to_numpy(), :]
