"""netCDF files people share: writing simulation output, reading and validating it.

Names, units and attributes follow docs/formats.md ("netCDF files"). Simulation files are streamed
chunk by chunk (memory stays bounded for 10⁷-event runs) into a temporary file that is renamed
only when complete. Derived datasets (Poincaré maps, sweeps, fits) are xarray Datasets written
with :func:`write_dataset`, also atomically.
"""

from __future__ import annotations

import math
import uuid
from pathlib import Path
from typing import TYPE_CHECKING, Any

import netCDF4
import numpy as np
import xarray as xr

from ..model.errors import InputError
from .atomic import atomic_path
from .records import KIND_NAMES, EventKind, StrobeColumn, TrajColumn

if TYPE_CHECKING:  # pragma: no cover - the engine's chunks, named in annotations only
    from ..engine.driver import Chunk

ENCODING = {"zlib": True, "complevel": 4}

#: (long_name, units) of every variable a simulation file may hold.
VARIABLES: dict[str, tuple[str, str]] = {
    "t_impact": (
        "nondimensional time t/t_c of the event (impact, or accumulation point of a chattering "
        "tail)",
        "1",
    ),
    "period_index": ("whole stator periods elapsed before the event (t = 0 starts period 0)", "1"),
    "t_impact_s": ("time of the event since t = 0", "s"),
    "phase": ("stator phase at the event, omega_s * t mod 2 pi", "rad"),
    "v_rel": ("relative normal velocity just before impact, v_s - v_rotor", "1"),
    "u_impact": ("axial position of the contact point at the event", "1"),
    "kind": ("kind of event", "1"),
    "omega_before": ("rotor angular velocity just before the event", "1"),
    "omega_after": ("rotor angular velocity just after the event", "1"),
    "time": ("nondimensional time t/t_c of the sample", "1"),
    "time_s": ("time of the sample since t = 0", "s"),
    "u_rotor": ("rotor axial position", "1"),
    "v_rotor": ("rotor axial velocity", "1"),
    "u_stator": ("stator axial position", "1"),
    "omega_rotor": ("rotor angular velocity", "1"),
    "period": ("stator period index (stroboscopic section at phase 0)", "1"),
    "strobe_t": ("time of the stroboscopic sample", "1"),
    "strobe_u": ("rotor axial position at phase 0", "1"),
    "strobe_v": ("rotor axial velocity at phase 0", "1"),
    "strobe_omega": ("rotor angular velocity at phase 0", "1"),
}
#: Variables of the trajectory's and the stroboscopic section's samples: name -> column of the
#: engine's records (``time_s`` is ``time`` in seconds, written apart).
TRAJ_VARIABLES = {
    "time": TrajColumn.T,
    "u_rotor": TrajColumn.U,
    "v_rotor": TrajColumn.V,
    "u_stator": TrajColumn.U_STATOR,
    "omega_rotor": TrajColumn.OMEGA,
}
STROBE_VARIABLES = {
    "period": StrobeColumn.PERIOD,
    "strobe_t": StrobeColumn.T,
    "strobe_u": StrobeColumn.U,
    "strobe_v": StrobeColumn.V,
    "strobe_omega": StrobeColumn.OMEGA,
}
REQUIRED_SIMULATION = ("t_impact", "phase", "v_rel", "kind")
REQUIRED_ATTRS = ("e", "omega_s", "status")


def _attr_value(v: Any) -> Any:
    if isinstance(v, bool):
        return int(v)
    if v is None:
        return "none"
    if isinstance(v, float | int | str | np.integer | np.floating):
        return v
    if isinstance(v, np.ndarray) and v.ndim == 1 and v.dtype.kind in "fiu":
        return v
    if isinstance(v, list | tuple) and v and all(isinstance(x, int | float) for x in v):
        return np.asarray(v)
    return str(v)


def period_index(t: np.ndarray, phase: np.ndarray, omega_s: float) -> np.ndarray:
    """Whole stator periods before each event, recovered exactly from ``t`` and ``phase``.

    The engine carries time as ``(n, θ)`` with ``t = (2πn + θ)/ω_s`` (kernel docstring); the
    rounding of ``t`` is far below half a period while ``ω_s t < 1e15``, so ``n`` is exact.
    """
    x = (np.asarray(t, dtype=float) * omega_s - np.asarray(phase, dtype=float)) / (2.0 * math.pi)
    return np.rint(x).astype(np.int64)


class SimulationWriter:
    """Stream a run into a netCDF file, atomically.

    Use as a context manager: the file appears at ``path`` after :meth:`close` with no error,
    and no file (and no temporary) is left if the block raises.
    """

    def __init__(
        self,
        path: str | Path,
        torsion: bool,
        events: bool,
        trajectory: bool,
        strobe: bool,
        chunk: int = 1 << 16,
        omega_s: float = 1.0,
        t_c: float | None = None,
        max_bytes: float = math.inf,
    ):
        self.path = Path(path)
        self.omega_s = omega_s
        self.t_c = t_c
        self.max_bytes = max_bytes
        self.torsion = torsion
        self.events = events
        self.trajectory = trajectory
        self.strobe = strobe
        self.chunk = chunk
        self.n_events = 0
        self.n_impacts = 0
        self.n_chatter = 0
        self.n_traj = 0
        self.n_strobe = 0
        self._ctx = None
        self._nc: netCDF4.Dataset | None = None

    def _var(self, name: str, dtype: str, dim: str) -> None:
        assert self._nc is not None
        var = self._nc.createVariable(
            name, dtype, (dim,), zlib=True, complevel=4, chunksizes=(self.chunk,), fill_value=False
        )
        # writes only append: a two-chunk cache is enough and keeps memory flat on long runs
        # (HDF5's default per-variable cache grows to tens of MB each)
        var.set_var_chunk_cache(size=2 * self.chunk * 8, nelems=17, preemption=1.0)
        long_name, units = VARIABLES[name]
        var.long_name = long_name
        var.units = units
        var.coverage_content_type = coverage_content_type(name, name == dim)

    def __enter__(self) -> SimulationWriter:
        self._ctx = atomic_path(self.path, suffix=".nc")
        tmp = self._ctx.__enter__()
        nc = netCDF4.Dataset(tmp, "w", format="NETCDF4")
        self._nc = nc
        nc.createDimension("impact", None)
        for name in ("t_impact", "phase", "v_rel", "u_impact"):
            self._var(name, "f8", "impact")
        # the exact time of an event is (period_index, phase): t_impact is derived from them and
        # loses resolution on long runs (t ~ 5e8 at omega_s = 1000 ties neighbouring impacts)
        self._var("period_index", "i8", "impact")
        nc["t_impact"].comment = (
            "derived: t_impact = (2 pi period_index + phase) / omega_s; the pair (period_index, "
            "phase) is exact, t_impact is rounded to double precision"
        )
        if self.t_c is not None:
            self._var("t_impact_s", "f8", "impact")
        self._var("kind", "i1", "impact")
        nc["kind"].flag_values = np.array(list(EventKind), dtype="i1")
        nc["kind"].flag_meanings = KIND_NAMES
        nc["phase"].valid_range = np.array([0.0, 2.0 * math.pi])
        if self.torsion:
            self._var("omega_before", "f8", "impact")
            self._var("omega_after", "f8", "impact")
        if self.trajectory:
            nc.createDimension("time", None)
            self._var("time", "f8", "time")
            # nondimensional: no CF standard_name/axis "T", which need units of time
            nc["time"].comment = "nondimensional time t/t_c (t_c = sqrt(U0/g_eff), docs/model.md)"
            if self.t_c is not None:  # elapsed seconds, no date: not a CF time (cf_time_attrs)
                self._var("time_s", "f8", "time")
            for name in ("u_rotor", "v_rotor", "u_stator"):
                self._var(name, "f8", "time")
            if self.torsion:
                self._var("omega_rotor", "f8", "time")
            if self.t_c is not None:  # CF: time_s is an auxiliary coordinate of the samples
                for name in ("u_rotor", "v_rotor", "u_stator", "omega_rotor"):
                    if name in nc.variables:
                        nc[name].coordinates = "time_s"
        if self.strobe:
            nc.createDimension("period", None)
            self._var("period", "i8", "period")
            for name in ("strobe_t", "strobe_u", "strobe_v"):
                self._var(name, "f8", "period")
            if self.torsion:
                self._var("strobe_omega", "f8", "period")
        return self

    def _bytes(self, n_events: int, n_traj: int, n_strobe: int) -> float:
        from .output_checks import file_row_bytes

        ev, tr, sb = file_row_bytes(self.torsion, self.t_c is not None)
        return (
            (n_events * ev if self.events else 0)
            + (n_traj * tr if self.trajectory else 0)
            + (n_strobe * sb if self.strobe else 0)
        )

    def append(self, c: Chunk) -> None:
        """Append one engine chunk.

        Raises
        ------
        InputError
            When the file would grow past ``max_bytes`` (the temporary file is then removed).
        """
        nc = self._nc
        assert nc is not None
        n = len(c.t)
        size = self._bytes(
            self.n_events + n, self.n_traj + len(c.traj), self.n_strobe + len(c.strobe)
        )
        if size > self.max_bytes:
            from .output_checks import too_large

            raise too_large(self.path, size, int(self.max_bytes), "this run")
        self.n_impacts += int(np.count_nonzero(c.kind == EventKind.IMPACT))
        self.n_chatter += int(np.count_nonzero(c.kind == EventKind.CHATTER))
        if n and self.events:
            a, b = self.n_events, self.n_events + n
            nc["t_impact"][a:b] = c.t
            nc["phase"][a:b] = c.phase
            nc["v_rel"][a:b] = c.v_rel
            nc["u_impact"][a:b] = c.u
            nc["kind"][a:b] = c.kind
            nc["period_index"][a:b] = period_index(c.t, c.phase, self.omega_s)
            if self.t_c is not None:
                nc["t_impact_s"][a:b] = c.t * self.t_c
            if self.torsion:
                nc["omega_before"][a:b] = c.omega_before
                nc["omega_after"][a:b] = c.omega_after
        self.n_events += n
        if len(c.traj) and self.trajectory:
            if self.t_c is not None:
                a, b = self.n_traj, self.n_traj + len(c.traj)
                nc["time_s"][a:b] = c.traj[:, TrajColumn.T] * self.t_c
            self.n_traj = self._put_samples(self.n_traj, c.traj, TRAJ_VARIABLES)
        if len(c.strobe) and self.strobe:
            self.n_strobe = self._put_samples(self.n_strobe, c.strobe, STROBE_VARIABLES)

    def _put_samples(self, start: int, rows: np.ndarray, columns: dict[str, int]) -> int:
        """Write the columns of ``rows`` from sample ``start`` into the variables of ``columns``
        the file holds (an integer variable takes its column truncated); returns the end."""
        assert self._nc is not None
        end = start + len(rows)
        for name, col in columns.items():
            if name in self._nc.variables:
                var = self._nc[name]
                var[start:end] = rows[:, col].astype(var.dtype)
        return end

    def set_attrs(self, attrs: dict[str, Any]) -> None:
        """Set global attributes (call before leaving the block)."""
        assert self._nc is not None
        attrs = {k: _attr_value(v) for k, v in attrs.items()}
        _file_attrs(attrs)
        if self.t_c is not None and self.trajectory and self.n_traj >= 2:  # samples in seconds
            t = self._nc["time_s"]
            attrs.update(time_coverage(t[self.n_traj - 1] - t[0], t[1] - t[0]))
        self._nc.setncatts(attrs)

    def __exit__(self, exc_type, exc, tb) -> None:
        # closing flushes the last chunks: on a full disk that is where the write fails, and the
        # temporary must still be removed (the atomic context sees the error either way)
        if self._nc is not None:
            nc, self._nc = self._nc, None
            try:
                nc.close()
            except (OSError, RuntimeError) as ex:
                if exc is None:
                    exc_type, exc, tb = type(ex), ex, ex.__traceback__
        assert self._ctx is not None
        ctx, self._ctx = self._ctx, None
        if exc is None:
            ctx.__exit__(None, None, None)
        elif not ctx.__exit__(exc_type, exc, tb):
            raise exc


def open_checked(
    path: str | Path,
    required: tuple[str, ...] = (),
    required_attrs: tuple[str, ...] = (),
    what: str = "netCDF",
    lazy: bool = False,
) -> xr.Dataset:
    """Open a netCDF file fully into memory, validating that it is readable and complete.

    With ``lazy`` the data stay on disk (memory stays flat whatever the file's size: a summary
    reads the header only); the caller closes the Dataset. String labels stored
    as CF labels are the index of their dimension again (:func:`labels_from_cf`).

    Raises
    ------
    InputError
        File missing, not netCDF, truncated or corrupt, or lacking a required variable or
        attribute.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(str(path), "", "file not found")
    if p.is_dir():
        raise InputError(str(path), "", f"is a directory, not a {what} file")
    if not p.is_file():  # a FIFO or device would block in open() (and ignore SIGTERM there)
        raise InputError(
            str(path), "", f"is not a regular file (a pipe or device?), not a {what} file"
        )
    try:
        if lazy:
            ds = xr.open_dataset(p, engine="netcdf4")
        else:
            with xr.open_dataset(p, engine="netcdf4") as ds:
                ds = ds.load()
    except Exception as ex:  # netCDF4/HDF5 raise a zoo of types for damaged files
        reason = str(ex).splitlines()[0][:120] if str(ex) else type(ex).__name__
        raise InputError(
            str(path), "", f"not a readable netCDF file (truncated or corrupt?): {reason}"
        ) from None
    restored = labels_from_cf(ds)
    if restored is not ds:  # closing the restored dataset closes the file (lazy)
        restored.set_close(ds.close)
        ds = restored
    for name in required:
        if name not in ds.variables:
            ds.close()
            raise InputError(str(path), name, f"missing required variable (not a {what} file?)")
    for name in required_attrs:
        if name not in ds.attrs:
            ds.close()
            raise InputError(str(path), name, f"missing required attribute (not a {what} file?)")
    return ds


def open_simulation(path: str | Path, lazy: bool = False) -> xr.Dataset:
    """Open and validate a simulation file (docs/formats.md variables and attributes).

    ``lazy`` (:func:`open_checked`) leaves the data on disk and skips the check of their values.
    """
    ds = open_checked(
        path, REQUIRED_SIMULATION, REQUIRED_ATTRS, what="bouncedisk simulation", lazy=lazy
    )
    n = ds.sizes.get("impact", 0)
    for name in REQUIRED_SIMULATION:
        if ds[name].dims != ("impact",):
            ds.close()
            raise InputError(str(path), name, "must have the single dimension 'impact'")
    if lazy:
        return ds
    if n and not np.all(np.isfinite(ds["t_impact"].values)):
        raise InputError(str(path), "t_impact", "contains non-finite values")
    return ds


def coverage_content_type(name: str, is_coordinate: bool) -> str:
    """ACDD-1.3 ``coverage_content_type`` of a variable: coordinates, measured data (names
    with ``measured``), else model results."""
    if is_coordinate:
        return "coordinate"
    return "physicalMeasurement" if "measured" in name else "modelResult"


def cf_time_attrs(attrs: dict) -> None:
    """Drop ``axis: T`` and ``standard_name: time`` from a variable whose units are not a
    reference time (``s``, ``1``): CF-1.10 §4.4 gives those to ``UNIT since DATE`` only, and an
    elapsed time since the start of a run or a measurement has no date."""
    units = str(attrs.get("units", ""))
    if " since " not in units:
        if attrs.get("axis") == "T":
            del attrs["axis"]
        if attrs.get("standard_name") == "time":
            del attrs["standard_name"]


def finalize(ds: xr.Dataset) -> xr.Dataset:
    """Give every variable ``units``, ``long_name`` (known names) and ACDD
    ``coverage_content_type``, and the file ``id``, dates, ``history`` and (time in seconds)
    time coverage, before writing."""
    for name, var in ds.variables.items():
        if name in VARIABLES:
            long_name, units = VARIABLES[name]
            var.attrs.setdefault("long_name", long_name)
            var.attrs.setdefault("units", units)
        var.attrs.setdefault("units", "1")
        var.attrs.setdefault("long_name", name.replace("_", " "))
        var.attrs.setdefault(
            "coverage_content_type", coverage_content_type(str(name), name in ds.coords)
        )
        cf_time_attrs(var.attrs)
    ds.attrs = {k: _attr_value(v) for k, v in ds.attrs.items()}
    _file_attrs(ds.attrs)
    for key, value in _time_coverage_of(ds).items():
        ds.attrs.setdefault(key, value)
    return ds


def _file_attrs(attrs: dict) -> None:
    """ACDD ``id`` (the run id, or a new one), the dates (now, for a file joined from parts
    whose dates differ) and CF ``history`` (when the writer gave none)."""
    from .. import __version__
    from .provenance import DATE_ATTRS, utc_now

    if "id" not in attrs:
        attrs["id"] = str(attrs.get("run_id") or f"bouncedisk-{uuid.uuid4().hex}")
    now = utc_now()
    for key in DATE_ATTRS:
        attrs.setdefault(key, attrs.get("date_created", now))
    if not str(attrs.get("history", "")).strip():
        attrs["history"] = f"{attrs['date_created']}: written by bouncedisk {__version__}"


def iso_seconds(x: float) -> str:
    """An ISO 8601 duration of ``x`` seconds to 10 significant digits (``PT0.00002S``: the
    differences of sample times carry their round-off, 0.11999999999999511 for 0.12)."""
    text = np.format_float_positional(float(x), precision=10, fractional=False, trim="-")
    return f"PT{text}S"


def time_coverage(duration_s: float, resolution_s: float) -> dict[str, str]:
    """ACDD-1.3 ``time_coverage_duration`` and ``time_coverage_resolution`` of samples in
    seconds (their span and spacing); the start and end are dates, which an elapsed time from
    an undated start has not."""
    return {
        "time_coverage_duration": iso_seconds(duration_s),
        "time_coverage_resolution": iso_seconds(resolution_s),
    }


#: Coordinates in seconds whose span is a file's time coverage (a fit's measured ``time``, a
#: physical scene's ``time_s``), the first found.
SECONDS_AXES = ("time", "time_s")


def _time_coverage_of(ds: xr.Dataset) -> dict[str, str]:
    """:func:`time_coverage` of the first of :data:`SECONDS_AXES` in seconds with two samples
    or more (resolution: the median spacing); empty if there is none."""
    for name in SECONDS_AXES:
        if name in ds.variables and ds[name].attrs.get("units") == "s" and ds[name].ndim == 1:
            t = ds[name].values.astype(float)
            t = t[np.isfinite(t)]
            if t.size >= 2:
                return time_coverage(t.max() - t.min(), float(np.median(np.diff(t))))
    return {}


#: Suffix of the dimension of string labels in a file (``branch`` labels ``branch_index``).
LABEL_DIM_SUFFIX = "_index"


def _is_text(var: xr.Variable) -> bool:
    """Whether a variable holds strings (numpy text, or objects that are all ``str``)."""
    if var.dtype.kind in "US":
        return True
    return var.dtype.kind == "O" and all(isinstance(v, str) for v in np.ravel(var.values))


def labels_to_cf(ds: xr.Dataset) -> xr.Dataset:
    """Store string-valued dimension coordinates as CF labels, for writing.

    CF-1.10 §1.3 defines a coordinate variable as numeric and monotonic, so the strings that
    label a dimension ``X`` (a load curve's ``branch``, a fit's ``parameter``) cannot be the
    coordinate variable ``X(X)``: the dimension becomes ``X_index``, without a coordinate
    variable, and ``X(X_index)`` is a string-valued auxiliary coordinate (§6.1, "Labels") that
    the data variables name in ``coordinates``. xarray reads ``X`` back as a coordinate
    (``ds.set_xindex("X")`` makes it selectable); :func:`labels_from_cf` restores ``X`` as the
    dimension and its index.

    Raises
    ------
    ValueError
        When the dataset already has a dimension of a label dimension's name.
    """
    names = [str(d) for d in ds.dims if d in ds.coords and _is_text(ds[d].variable)]
    clash = [n + LABEL_DIM_SUFFIX for n in names if n + LABEL_DIM_SUFFIX in ds.dims]
    if clash:
        raise ValueError(f"cannot store string labels: dimensions {clash} already exist")
    if not names:
        return ds
    return ds.drop_indexes(names).rename_dims({n: n + LABEL_DIM_SUFFIX for n in names})


def labels_from_cf(ds: xr.Dataset) -> xr.Dataset:
    """Labels stored by :func:`labels_to_cf` as ``X(X_index)``, back as the dimension ``X``
    with its index (a file that stores the labels as ``X(X)`` is returned as it is)."""
    for dim in [str(d) for d in ds.dims if str(d).endswith(LABEL_DIM_SUFFIX)]:
        name = dim[: -len(LABEL_DIM_SUFFIX)]
        if name in ds.variables and ds[name].dims == (dim,) and name not in ds.dims:
            if _is_text(ds[name].variable):
                ds = ds.set_coords(name).swap_dims({dim: name})
    return ds


def write_dataset(ds: xr.Dataset, path: str | Path) -> None:
    """Write an xarray Dataset to netCDF (zlib-compressed numeric variables), atomically;
    string-valued dimension coordinates are stored as CF labels (:func:`labels_to_cf`)."""
    ds = labels_to_cf(finalize(ds))
    enc = {}
    for name, var in ds.variables.items():
        if var.dtype.kind in "fiu" and var.ndim > 0:
            enc[name] = dict(ENCODING)
        if name in ds.dims and var.dtype.kind == "f":  # CF §2.5.1: no _FillValue on coordinates
            enc.setdefault(name, {})["_FillValue"] = None
    with atomic_path(path, suffix=".nc") as tmp:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=enc)
