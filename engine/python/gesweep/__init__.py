"""gesweep from Python: the engine's functions on NumPy arrays, and the archives as xarray Datasets.

    import gesweep                                   # PYTHONPATH=build/python (docs/python.md)
    ance = gesweep.Aircraft.load("studies/aircraft/ance.toml")
    b = gesweep.boundary(ance, 32.0208)              # H*, every crossing (and sensitivities=True)
    m = gesweep.modes(ance, heights, speeds)         # vectorised: eigenvalues N x 5, sigma, modes
    r = gesweep.simulate(ance, 2.5935, 32.0208, pulse_amplitude_deg=5, pulse_duration_s=0.2)
    gesweep.run("studies/stability_map.toml", "results/stability_map.h5")
    ds = gesweep.open_archive("results/stability_map.h5")

Every function calls the engine, not the command line (no process per call), and releases the GIL
while it computes. Bad input raises gesweep.InputError (a ValueError, and a TypeError for an argument of
the wrong type) with the one line the gesweep command prints. docs/python.md documents the whole API.
"""

import inspect as _inspect
import os as _os
from collections import namedtuple as _namedtuple

import numpy as _np

from . import _gesweep
from ._gesweep import ArchiveError, InputError
from ._archive import ArchiveNote, list_products, open_archive

__version__ = _gesweep.__version__
__all__ = ["Aircraft", "modes", "boundary", "simulate", "land", "run", "open_archive", "list_products",
           "InputError", "ArchiveError", "ArchiveNote", "MODEL_OPTIONS", "CLASSIFICATION_LEVELS"]

#: The model options of docs/model.md that modes, boundary, simulate and land take as keywords:
#: (key, default, description), from their description (ModelOptions::Describe) and, for the scale
#: factors and the mass properties, the module's list (engine/python/support.h).
MODEL_OPTIONS = tuple((s["key"], s["default"], s["doc"]) for s in _gesweep.model_options())

#: The names of the codes of modes(...)["classification"] (0, 1, 2, 3).
CLASSIFICATION_LEVELS = tuple(_gesweep.classification_levels())

_MODEL_DOC = "\n".join(f"    {k} = {d!r}: {doc}" for k, d, doc in MODEL_OPTIONS)


def _model_parameters():
    return [_inspect.Parameter(k, _inspect.Parameter.KEYWORD_ONLY, default=d) for k, d, _ in MODEL_OPTIONS]


def _input_error(key, value, expected):
    """An InputError about an argument, worded as the engine's: "argument: key = value: expected"."""
    error = InputError(f"argument: {key} = {value!r}: {expected}")
    error.source, error.key, error.value, error.expected = "argument", key, repr(value), expected
    return error


def _numbers(value, key):
    """`value` as a float array; InputError naming `key` when it is not numbers."""
    try:
        return _np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise _input_error(key, value, "expected a number or an array of numbers") from None


def _aircraft(aircraft):
    """The native aircraft of an Aircraft; InputError naming `aircraft` for anything else (a path
    included: gesweep.Aircraft.load(path) makes one)."""
    if not isinstance(aircraft, Aircraft):
        hint = (" (load it first: gesweep.Aircraft.load(path))"
                if isinstance(aircraft, (str, bytes, _os.PathLike)) else "")
        raise _input_error("aircraft", aircraft, "expected a gesweep.Aircraft" + hint)
    return aircraft._native


def _flag(value, key):
    """`value` when it is True or False (a NumPy bool too); InputError naming `key` otherwise."""
    if isinstance(value, (bool, _np.bool_)):
        return bool(value)
    raise _input_error(key, value, "expected True or False")


def _threads(threads):
    """The worker threads as the engine takes them (0: every core); InputError naming `threads`."""
    if threads is None:
        return 0
    if isinstance(threads, (bool, _np.bool_)) or not isinstance(threads, (int, _np.integer)):
        raise _input_error("threads", threads, "expected a whole number of worker threads, 1 to 4096, or None")
    if not 1 <= int(threads) <= 4096:
        raise _input_error("threads", threads, "expected 1 to 4096 worker threads, or None")
    return int(threads)


def _path(value, key):
    """A path argument as a str; InputError naming `key` when it is not a str or os.PathLike."""
    try:
        name = _os.fspath(value)
    except TypeError:
        raise _input_error(key, value, "expected a path (str or os.PathLike)") from None
    return _os.fsdecode(name) if isinstance(name, bytes) else name


def _given(options):
    """The keyword arguments given, less those left at None (the engine's default)."""
    return {k: v for k, v in options.items() if v is not None}


class Aircraft:
    """An aircraft file, loaded and validated once (schemas/aircraft.schema.json).

    Attributes: name, source_path, wingspan_m, mean_chord_m, wing_area_m2, mass_kg, pitch_inertia_kgm2,
    cg_over_chord, CDo, stall_speed_mps, wheel_contact_height_m, field_elevation_m (SI units).
    """

    def __init__(self, native):
        self._native = native
        for key, value in native.facts().items():
            setattr(self, key, value)

    @classmethod
    def load(cls, path):
        """Loads an aircraft file (TOML). Raises InputError naming the file, key, value and line."""
        return cls(_gesweep.NativeAircraft.load(_path(path, "path")))

    @property
    def table(self):
        """The coefficient table against height as a pandas DataFrame: a column height_m (the
        free-flight row last, height inf) and one column per tabulated coefficient, named as in the
        aircraft file; units in ``table.attrs["units"]`` (per radian and dimensionless; CLh, CMh are
        derivatives with respect to h = H/c)."""
        import pandas as pd
        frame = pd.DataFrame(self._native.table())
        units = {name: "1" for name in frame.columns}
        units["height_m"] = "m"
        frame.attrs["units"] = units
        frame.attrs["aircraft"] = self.name
        return frame

    def __repr__(self):
        return f"gesweep.Aircraft({self.name!r} from {self.source_path!r})"


def modes(aircraft, height_m, speed_mps, *, threads=None, out=None, **model_options):
    """The eigen-analysis of Eq. (1) at every (height_m, speed_mps) pair (docs/model.md section 6).

    height_m, speed_mps: numbers or arrays (broadcast together; inf is free flight), m and m/s.
    Runs in parallel on `threads` threads (None: all cores) with the GIL released, no Python per point.
    Returns a dict of NumPy arrays of the broadcast shape S, named as the archive's results/modes columns:
      eigenvalues (S + (5,), complex, 1/s): short period (2), phugoid (2), height (1), a pair Im > 0 first
      stability_margin_per_s (1/s): sigma, the largest Re, the neutral height root left out
      stable (bool): sigma < 0;  classification (int8): codes of CLASSIFICATION_LEVELS
      height_over_span (1)
      <mode>/eigenvalue_re_per_s, <mode>/eigenvalue_im_per_s (1/s), <mode>/natural_frequency_radps,
      <mode>/damping_ratio (1), <mode>/period_s (s), <mode>/time_to_half_or_double_s (s),
      <mode>/oscillatory, <mode>/neutral (bool), for <mode> in short_period, phugoid, height.
    out: the dict of an earlier call with the same shape S, written in place and returned (no new
    memory: for repeated calls over large arrays, as NumPy's out=).
    Model options (keywords):
"""
    native = _aircraft(aircraft)
    threads = _threads(threads)
    height, speed = _numbers(height_m, "height_m"), _numbers(speed_mps, "speed_mps")
    try:
        h, u = _np.broadcast_arrays(height, speed)
    except ValueError:
        raise _input_error("speed_mps", f"an array of shape {speed.shape}",
                           f"expected a shape that broadcasts with height_m's {height.shape}") from None
    shape = h.shape
    flat = None if out is None else _flat_outputs(out, shape)
    result = _gesweep.modes(native, _np.ascontiguousarray(h).ravel(), _np.ascontiguousarray(u).ravel(),
                            threads, flat, **_given(model_options))
    if out is not None:
        return out
    return {k: v.reshape(shape + v.shape[1:]) for k, v in result.items()}


def _flat_outputs(out, shape):
    """modes' `out` as flat views (the engine checks the names, dtypes and sizes); InputError when an
    array is not of shape S + (...) or not C-contiguous, since its flat form would be a copy."""
    if not isinstance(out, dict):
        raise _input_error("out", out, "expected the dict of an earlier gesweep.modes call, or None")
    flat = {}
    for key, value in out.items():
        if not (isinstance(value, _np.ndarray) and value.shape[:len(shape)] == shape and value.flags.c_contiguous):
            raise _input_error(f"out[{key!r}]", value if not isinstance(value, _np.ndarray) else
                               f"an array of shape {value.shape}",
                               f"expected a C-contiguous array of shape {shape} + (...)")
        flat[key] = value.reshape((int(_np.prod(shape, dtype=_np.int64)),) + value.shape[len(shape):])
    return flat


modes.__doc__ += _MODEL_DOC
modes.__signature__ = _inspect.Signature(
    [_inspect.Parameter(n, _inspect.Parameter.POSITIONAL_OR_KEYWORD) for n in ("aircraft", "height_m", "speed_mps")]
    + [_inspect.Parameter("threads", _inspect.Parameter.KEYWORD_ONLY, default=None),
       _inspect.Parameter("out", _inspect.Parameter.KEYWORD_ONLY, default=None)] + _model_parameters())


def boundary(aircraft, speed_mps, *, method="hurwitz", sensitivities=False, **model_options):
    """The stability boundary H*(u0) at one speed (docs/model.md section 6), as `gesweep boundary`.

    method: 'hurwitz' (every crossing of the imaginary axis, certified) or 'sampled' (the former search).
    sensitivities: also dH*/dp for every coefficient scale factor, CDo, mass, Iy and speed, ranked by
    |p dH*/dp| (docs/sensitivity.md).
    Returns a dict with the keys of `gesweep boundary --format json`'s rows: speed_mps, height_m (H*, m;
    nan when none), height_over_span, other_crossings_m, crossings (list of dicts: height_m, kind,
    mode, eigenvalue (complex), stable_above, ...), method, certified, certificate, scanned_range_m,
    reason ('' when there is a boundary), and with sensitivities: sensitivities (list of dicts),
    sensitivity_mode, dsigma_dH_per_s_per_m, no_effect_parameters.
    A list of speeds gives a list of such dicts.
    Model options (keywords):
"""
    native = _aircraft(aircraft)
    if not isinstance(method, str):
        raise _input_error("method", method, "expected 'hurwitz' or 'sampled'")
    sensitivities = _flag(sensitivities, "sensitivities")
    options = _given(model_options) if model_options else model_options
    if isinstance(speed_mps, (float, int)) and not isinstance(speed_mps, bool):  # without NumPy's conversion
        return _gesweep.boundary(native, speed_mps, method, sensitivities, **options)
    speeds = _numbers(speed_mps, "speed_mps")
    if speeds.ndim > 0:
        return [_gesweep.boundary(native, float(u), method, sensitivities, **options) for u in speeds.ravel()]
    return _gesweep.boundary(native, speed_mps, method, sensitivities, **options)


boundary.__doc__ += _MODEL_DOC
boundary.__signature__ = _inspect.Signature(
    [_inspect.Parameter(n, _inspect.Parameter.POSITIONAL_OR_KEYWORD) for n in ("aircraft", "speed_mps")]
    + [_inspect.Parameter("method", _inspect.Parameter.KEYWORD_ONLY, default="hurwitz"),
       _inspect.Parameter("sensitivities", _inspect.Parameter.KEYWORD_ONLY, default=False)]
    + _model_parameters())

#: What simulate and land return: the settings used (dict), the summary (dict) and the series
#: (pandas DataFrame, columns named with their units as in the CSV; None with summary_only=True).
Response = _namedtuple("Response", ["run", "summary", "series"])


def _frame(columns):
    if columns is None:
        return None
    import pandas as pd
    return pd.DataFrame(columns)


def _settings_doc(settings):
    lines = []
    for s in settings:
        unit = f" [{s['unit']}]" if s.get("unit") not in (None, "1") else ""
        choices = f" (one of {', '.join(s['choices'])})" if s.get("choices") else ""
        allowed = f"; {s['range']}" if s.get("range") else ""
        lines.append(f"    {s['key']} = {s['default']!r}{unit}: {s['doc']}{choices}{allowed}")
    return "\n".join(lines)


_SIMULATE_SETTINGS = _gesweep.simulate_settings()
_LAND_SETTINGS = _gesweep.land_settings()


def simulate(aircraft, height_m, speed_mps, *, summary_only=False, output_dt_s=None, **options):
    """One open-loop time response of Eq. (1) after an elevator input, the derivatives re-evaluated at
    the current height and speed (docs/model.md section 7, docs/simulation.md), as `gesweep simulate`.

    height_m: start height H0, m; speed_mps: reference speed u0, m/s. output_dt_s: the series' sampling
    interval, s (None: the step). Ctrl-C (KeyboardInterrupt) stops it within a step.
    Returns Response(run, summary, series): run and summary are dicts with the keys of
    `gesweep simulate --format json` (numbers in the key's unit; nan where the JSON has null), series a
    pandas DataFrame with the CSV's columns (time_s, height_m, speed_mps, delta_u_mps, delta_w_mps,
    pitch_rate_radps, delta_theta_rad, delta_h_m, elevator_rad; u_g_mps, w_g_mps with a disturbance),
    or None with summary_only=True.
    Settings (keywords; the fields of the engine's OpenLoopConfig, as `gesweep simulate --help`):
"""
    run_, summary, series = _gesweep.simulate(_aircraft(aircraft), height_m, speed_mps, summary_only, output_dt_s,
                                              **_given(options))
    return Response(run_, summary, _frame(series))


simulate.__doc__ += _settings_doc(_SIMULATE_SETTINGS) + "\n    Model options (keywords):\n" + _MODEL_DOC
simulate.__signature__ = _inspect.Signature(
    [_inspect.Parameter(n, _inspect.Parameter.POSITIONAL_OR_KEYWORD) for n in ("aircraft", "height_m", "speed_mps")]
    + [_inspect.Parameter("summary_only", _inspect.Parameter.KEYWORD_ONLY, default=False),
       _inspect.Parameter("output_dt_s", _inspect.Parameter.KEYWORD_ONLY, default=None)]
    + [_inspect.Parameter(s["key"], _inspect.Parameter.KEYWORD_ONLY, default=s["default"]) for s in _SIMULATE_SETTINGS]
    + _model_parameters())


def land(aircraft, *, summary_only=False, **options):
    """The closed-loop automatic landing (docs/model.md section 8, docs/landing.md), as `gesweep land`.

    Returns Response(run, summary, series): run and summary with the keys of
    `gesweep land --format json` (outcome: landed, no_touchdown, stall, diverged or design_failed;
    design: the gain and the closed-loop eigenvalues; nan where the JSON has null), series a DataFrame
    with the CSV's columns (angles in degrees; u_g_mps, w_g_mps (and q_g_radps) with a disturbance)
    and phase. A failed design is data (outcome 'design_failed'), not an exception. Ctrl-C
    (KeyboardInterrupt) stops it within a step.
    Settings (keywords; the fields of the engine's LandingConfig, as `gesweep land --help`; nan:
    automatic, as the text says):
"""
    run_, summary, series = _gesweep.land(_aircraft(aircraft), summary_only, **_given(options))
    return Response(run_, summary, _frame(series))


land.__doc__ += _settings_doc(_LAND_SETTINGS) + "\n    Model options (keywords):\n" + _MODEL_DOC
land.__signature__ = _inspect.Signature(
    [_inspect.Parameter("aircraft", _inspect.Parameter.POSITIONAL_OR_KEYWORD),
     _inspect.Parameter("summary_only", _inspect.Parameter.KEYWORD_ONLY, default=False)]
    + [_inspect.Parameter(s["key"], _inspect.Parameter.KEYWORD_ONLY, default=s["default"]) for s in _LAND_SETTINGS]
    + _model_parameters())


def run(study_path, archive_path, *, threads=None, progress=None, resume=False, force=False, shard=None):
    """Runs a study file's sweep into an HDF5 archive (schemas/archive.md), as `gesweep run`.

    threads: worker threads (None: all cores). progress: called as progress(done, to_do) about every
    50 ms and at the end. resume=True continues an existing archive; force=True replaces one; shard:
    "i/N". The GIL is released while the sweep runs. KeyboardInterrupt (Ctrl-C) stops it between two
    integration steps, closes the archive with every complete batch kept, and is raised again:
    run(..., resume=True) completes it, equal bit for bit to an uninterrupted run.
    Failed runs are data (status 2 in the archive), counted in the result: a dict with archive, runs,
    runs_run, runs_ok, runs_failed, runs_pending, cancelled, threads, seconds.
    """
    # Every argument checked before any work: a wrong one is refused at once, not after the sweep.
    study = _path(study_path, "study_path")
    archive = _path(archive_path, "archive_path")
    workers = _threads(threads)
    if progress is not None and not callable(progress):
        raise _input_error("progress", progress, "expected a function progress(done, to_do), or None")
    resume = _flag(resume, "resume")
    force = _flag(force, "force")
    if shard is not None and not isinstance(shard, str):
        raise _input_error("shard", shard, "expected a string 'i/N' (0 <= i < N), or None")
    return _gesweep.run(study, archive, workers, progress, resume, force, shard or "")
