"""What every machine shares: the error catalogue, pose checking and the pose error."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import errors as _errors
from ..kinematics import pose_difference

#: the columns of a pose error with a rotation-vector orientation part (Rx, Ry, Rz: rad);
#: a machine whose orientation output is the change of the tool-axis direction names them
#: Vx, Vy, Vz instead (``machine.components``)
POSE_COMPONENTS = ("Px", "Py", "Pz", "Rx", "Ry", "Rz")


class Machine:
    """Base class: subclasses set ``name``, ``axes``, ``tool_offsets``, ``catalogue`` and
    implement ``transforms(errors, pose) -> (actual, ideal)`` (each ``(n, 4, 4)``: the tool
    frame in the workpiece frame)."""

    name: str = ""
    axes: tuple[str, ...] = ()
    tool_offsets: tuple[str, ...] = ()
    catalogue: tuple[_errors.ErrorSpec, ...] = ()
    components: tuple[str, ...] = POSE_COMPONENTS

    @property
    def error_names(self) -> list[str]:
        """list of str: the error symbols in catalogue order (the columns of an error array)."""
        return _errors.symbols(self.catalogue)

    @property
    def n_errors(self) -> int:
        """int: the number of errors of the catalogue."""
        return len(self.catalogue)

    def check_errors(self, errors) -> np.ndarray:
        """Validate an error array against the catalogue.

        Parameters
        ----------
        errors : (n, n_errors) array_like
            Error values in mm and rad, columns in catalogue order (:attr:`error_names`).

        Returns
        -------
        (n, n_errors) ndarray of float
            ``errors`` as a float array.

        Raises
        ------
        ValueError
            If ``errors`` is not two-dimensional with ``n_errors`` columns.
        """
        e = np.asarray(errors, dtype=float)
        if e.ndim != 2 or e.shape[1] != self.n_errors:
            raise ValueError(
                f"errors for {self.name} must have shape (n, {self.n_errors}) "
                f"(columns: {', '.join(self.error_names)}), got {e.shape}"
            )
        return e

    def check_pose(self, pose: Mapping, n: int) -> dict[str, np.ndarray]:
        """Validate a pose mapping; axes are required, tool offsets default to 0.

        Parameters
        ----------
        pose : mapping of str to float or (n,) array
            Axis positions (linear axes mm, rotary axes rad) by pose name (:attr:`axes`)
            and, optionally, tool offsets (mm, :attr:`tool_offsets`).
        n : int
            The number of samples every value is broadcast to.

        Returns
        -------
        dict of str to (n,) ndarray
            Every axis and tool offset name, each broadcast to ``(n,)`` (read-only views).

        Raises
        ------
        TypeError
            If ``pose`` is not a mapping.
        ValueError
            If a name is unknown, an axis is missing or a value is neither a scalar nor of
            shape ``(n,)`` (or ``(1,)``).
        """
        if not isinstance(pose, Mapping):
            raise TypeError(f"pose must be a mapping of {self.axes + self.tool_offsets}")
        allowed = self.axes + self.tool_offsets
        unknown = [k for k in pose if k not in allowed]
        if unknown:
            raise ValueError(f"unknown pose name(s) {unknown} for {self.name}; "
                             f"allowed: {', '.join(allowed)}")
        missing = [a for a in self.axes if a not in pose]
        if missing:
            raise ValueError(f"pose for {self.name} lacks axis value(s) {missing}")
        out = {}
        for k in allowed:
            v = np.asarray(pose.get(k, 0.0), dtype=float)
            if v.ndim > 1 or (v.ndim == 1 and v.shape[0] not in (1, n)):
                raise ValueError(f"pose[{k!r}] must be a scalar or have shape ({n},), "
                                 f"got {v.shape}")
            out[k] = np.broadcast_to(v, (n,))
        return out

    def transforms(self, errors: np.ndarray, pose: Mapping) -> tuple[np.ndarray, np.ndarray]:
        """The actual and the ideal tool frame in the workpiece frame (subclasses implement it).

        Parameters
        ----------
        errors : (n, n_errors) array
            Error values in mm and rad, columns in catalogue order.
        pose : mapping of str to float or (n,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        actual, ideal : (n, 4, 4) ndarray
            Homogeneous transforms (translations in mm) with and without the errors.
        """
        raise NotImplementedError

    def pose_error(self, errors, pose: Mapping) -> np.ndarray:
        """The pose error of the tool in the workpiece frame, actual minus ideal.

        From the full (untruncated) matrix product of :meth:`transforms`, via
        :func:`mtaccuracy.kinematics.pose_difference`.

        Parameters
        ----------
        errors : (n, n_errors) array
            Error values in mm and rad, columns in catalogue order.
        pose : mapping of str to float or (n,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        (n, 6) ndarray
            ``Px, Py, Pz`` (mm) and ``Rx, Ry, Rz`` (rad: the rotation vector
            ``vee(R_actual R_ideal^T)``).
        """
        actual, ideal = self.transforms(errors, pose)
        return pose_difference(actual, ideal)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}: {self.n_errors} errors, axes {self.axes}>"

    def jacobian(self, pose: Mapping, step: float = 1e-6) -> np.ndarray:
        """d(pose error)/d(errors) at zero errors by central differences.

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm) of P poses.
        step : float
            Central-difference step, mm or rad; the model is smooth, so the result is exact
            to about ``step**2``.

        Returns
        -------
        (P, 6, n_errors) ndarray
            Row ``[p, i, j]`` is d(pose error component i)/d(error j) at pose p
            (``(1, 6, n_errors)`` for a scalar pose); translational errors give
            dimensionless coefficients, angular errors mm per rad.
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n_poses = max(v.shape[0] for v in vals.values())
        d = self.n_errors
        eye = np.eye(d) * step
        e = np.concatenate([eye, -eye])                                   # (2d, d)
        rows = np.tile(e, (n_poses, 1))
        rep = {k: np.repeat(np.broadcast_to(v, (n_poses,)), 2 * d) for k, v in vals.items()}
        pe = self.pose_error(rows, rep).reshape(n_poses, 2, d, 6)
        return np.swapaxes((pe[:, 0] - pe[:, 1]) / (2 * step), 1, 2)

