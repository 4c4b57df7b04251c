"""The thermal measurement schema of ``data/thermal/README.md``: names, units, limits, errors.

What a dataset of one axis holds and how it is refused: the three files
(:data:`TEMPERATURES_FILE`, :data:`ERRORS_FILE`, the optional :data:`EXPERIMENTS_FILE`), the
unit every column name carries, the plausible range of each quantity and the size limits, and
the error and warnings the readers raise (:class:`DataFormatError`, naming the file and the
problem; :class:`DroppedSensorWarning` and :class:`IgnoredColumnWarning` for what they set
aside).  Reading: :mod:`~mtaccuracy.thermal.io`; the checks: :mod:`~mtaccuracy.thermal.checks`.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

__all__ = [
    "DataFormatError", "DroppedSensorWarning", "IgnoredColumnWarning",
    "TEMPERATURES_FILE", "ERRORS_FILE", "EXPERIMENTS_FILE", "TEMPERATURE_RANGE_C",
    "ERROR_LIMIT_UM", "ERROR_MIN_SPAN_UM", "POSITION_MIN_SPAN_MM", "POSITION_LIMIT_MM",
    "MIN_SENSORS", "MAX_SENSORS", "MAX_POSITIONS", "MAX_MEASUREMENTS", "MAX_FILE_BYTES",
    "InterpolatedGapWarning", "LAB_TEMPERATURES_SUFFIX", "LAB_LASER_SUFFIX", "SHORT_GAP_MIN",
]

TEMPERATURES_FILE = "temperatures.csv"
ERRORS_FILE = "errors.csv"
EXPERIMENTS_FILE = "experiments.csv"
_TEMP_UNIT = "_degC"
#: The columns that identify a measurement in ``temperatures.csv`` (and, but for the time, in
#: ``errors.csv``).
_KEYS = ("experiment", "measurement", "time_min")
#: Plausible values of each quantity, refused outside (the limits are in the message).
#: Temperatures (degC): a machine shop's air, structure, drives and motor windings lie within
#: -30..200 degC (insulation class H is rated to 180 degC); a temperature in kelvin does not
#: (any shop above -30 degC reads above 243 K).
TEMPERATURE_RANGE_C = (-30.0, 200.0)
#: Errors (um): a machine tool's positioning error stays within +-1000 um (1 mm); larger
#: readings are most likely in nm.  Over a whole file the errors span at least 1 um: the pitch
#: error, the warm-up drift and the interferometer's own scatter each reach that; a file whose
#: errors all lie within 1 um is most likely in mm.
ERROR_LIMIT_UM = 1000.0
ERROR_MIN_SPAN_UM = 1.0
#: Target positions (mm): they span at least 1 mm and lie within +-100 m; positions in m span
#: less than 1 mm over any machine-tool axis shorter than 1 km.
POSITION_MIN_SPAN_MM = 1.0
POSITION_LIMIT_MM = 1e5
#: Size limits of a readable dataset, so that a run stays within memory and time on a small
#: machine: the fuzzy closure holds n_sensors**3 numbers, the point-by-point selection runs
#: once per position, and the SVR search's time grows with the measurements (its grid bounded
#: by :data:`mtaccuracy.thermal.SVR_MAX_CN`): at the limits one train/test split of notebook 04
#: takes about 50 s, the whole notebook about 8 min on 2 cores, 0.6 GB.
MAX_SENSORS = 100
#: At least this many working sensors (after dead ones are dropped): the clustering and the
#: selection of sensitive points need a choice.
MIN_SENSORS = 3
MAX_POSITIONS = 500
MAX_MEASUREMENTS = 1000
#: A file larger than this is refused before it is read (errors.csv at the limits above, 500 000
#: rows, takes about 15 MB).
MAX_FILE_BYTES = 100_000_000


#: A lab export (``data/thermal/README.md``): per experiment a logger file
#: ``<experiment>_temperatures.csv`` and a laser file ``<experiment>_laser.csv``.
LAB_TEMPERATURES_SUFFIX = "_temperatures.csv"
LAB_LASER_SUFFIX = "_laser.csv"
#: A gap in a logged sensor (blank or NaN cells) is *short*, and interpolated linearly in time,
#: when the readings on either side of it lie at most this many minutes apart; a longer gap, or
#: one at the start or end of the log, drops the sensor.  Why 3 min: linear interpolation over
#: a span h misses a smooth temperature by at most ``h**2 / 8 * max|T''|``; a first-order
#: thermal node of rise dT and time constant tau has ``|T''| <= dT / tau**2``, and the fastest
#: node a machine-tool thermal test logs (a motor winding, tau >= 10 min, dT <= 10 degC in a
#: warm-up)
#: then moves off the line by at most 9 / 8 * 10 / 100 = 0.11 degC over 3 min, the resolution
#: of a 0.1 degC logger (0.03 degC for tau = 20 min).  At 30 s per sample, up to 5 missing
#: samples; at 1 min, up to 2.
SHORT_GAP_MIN = 3.0


class DataFormatError(ValueError):
    """A measurement file breaks the CSV schema; the message names the file and the problem."""


class DroppedSensorWarning(UserWarning):
    """A dead sensor was dropped by :func:`~mtaccuracy.thermal.io.read_measurements`.

    Dead: its reading never changes within an experiment, or it holds no number.  The message
    names the file, the sensor and the value.
    """


class InterpolatedGapWarning(UserWarning):
    """Short gaps of a logged sensor (blank or NaN cells) were interpolated linearly in time.

    Raised by :func:`~mtaccuracy.thermal.io.read_measurements` on a lab export, once per sensor
    and logger file; the message names the file, the sensor, the experiment and the lines.  A
    gap longer than :data:`SHORT_GAP_MIN` drops the sensor instead
    (:class:`DroppedSensorWarning`).
    """


class IgnoredColumnWarning(UserWarning):
    """Columns outside the schema (``spindle_speed_rpm``, ``note``) were ignored on reading.

    Raised by :func:`~mtaccuracy.thermal.io.read_measurements`; the message names the file and the
    columns.
    """



def _problem(path, message) -> DataFormatError:
    return DataFormatError(f"{path}: {message}")
