"""NetCDF intermediates with units and provenance, written atomically.

Every intermediate of the pipeline goes through :func:`write_dataset`:

* explicit engine (``h5netcdf``), zlib compression of every data variable;
* CF-style ``units`` and ``long_name`` required on every variable and coordinate;
* provenance attributes: ``config_json`` (the sub-config used), ``config_sha256``,
  ``seed_spawn_key``, ``railradio_version``, ``git_commit``, ``arithmetic`` (the CPU code
  paths of NumPy and OpenBLAS the output was computed with);
* complex variables stored portably as ``<name>_real``/``<name>_imag`` (read back by
  :func:`read_dataset`);
* atomic: written to a hidden temporary file in the target folder, then renamed, so an
  interrupted job never leaves a half-written file under the target name.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import subprocess
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

# HDF5 file locking fails on many network filesystems (cluster scratch); our writes are
# atomic renames of private temporary files, so locking buys nothing.  Before h5py loads.
os.environ.setdefault("HDF5_USE_FILE_LOCKING", "FALSE")

import numpy as np
import xarray as xr

from railradio import __version__
from railradio.arithmetic import in_effect
from railradio.rng import canonical_json

ENGINE = "h5netcdf"
PROVENANCE_ATTRS = ("config_json", "config_sha256", "seed_spawn_key", "railradio_version", "git_commit", "arithmetic")


def git_commit() -> str:
    """The current git commit of the source tree (``+dirty`` if modified), or ``unknown``."""
    here = Path(__file__).resolve().parent
    try:
        sha = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, check=True, timeout=10
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "."],
            cwd=here,
            capture_output=True,
            text=True,
            check=True,
            timeout=10,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return sha + ("+dirty" if dirty else "")


def provenance(config: Mapping[str, Any], key: tuple[int, ...] | None) -> dict[str, str]:
    """The provenance attributes of an output made with ``config`` and spawn key ``key``."""
    cfg = canonical_json(config)
    return {
        "config_json": cfg,
        "config_sha256": hashlib.sha256(cfg.encode("utf-8")).hexdigest(),
        "seed_spawn_key": json.dumps(list(key) if key is not None else None),
        "railradio_version": __version__,
        "git_commit": git_commit(),
        "arithmetic": json.dumps(in_effect(), sort_keys=True),  # CPU code paths (railradio.arithmetic)
    }


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    On any exception (``KeyboardInterrupt`` and ``SystemExit`` included) the temporary
    file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)  # mkstemp makes 0600; outputs are ordinary files
    try:
        yield tmp_path
        os.replace(tmp_path, path)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_json(path: str | os.PathLike[str], obj: Any) -> None:
    """Write ``obj`` as indented, key-sorted JSON to ``path`` atomically."""
    write_text(path, json.dumps(obj, indent=2, sort_keys=True, allow_nan=False) + "\n")


def _check_attrs(ds: xr.Dataset) -> None:
    for name, var in {**ds.data_vars, **ds.coords}.items():
        missing = [a for a in ("units", "long_name") if a not in var.attrs]
        if missing:
            raise ValueError(
                f"variable {name!r} lacks attribute(s) {missing}; every variable needs 'units' and 'long_name'"
            )


def _split_complex(ds: xr.Dataset) -> xr.Dataset:
    out = ds.copy()
    for name in list(ds.data_vars):
        var = ds[name]
        if np.iscomplexobj(var.values):
            attrs = dict(var.attrs)
            for part, fn in (("real", np.real), ("imag", np.imag)):
                out[f"{name}_{part}"] = var.copy(data=fn(var.values))
                out[f"{name}_{part}"].attrs = {
                    **attrs,
                    "long_name": f"{attrs['long_name']} ({part} part)",
                    "complex_part": part,
                }
            out = out.drop_vars(name)
    return out


def write_dataset(
    ds: xr.Dataset, path: str | os.PathLike[str], config: Mapping[str, Any], key: tuple[int, ...] | None, title: str
) -> None:
    """Write ``ds`` to NetCDF at ``path`` with provenance, atomically.

    Parameters
    ----------
    ds
        The dataset; every variable and coordinate must carry ``units`` and ``long_name``.
    path
        Target ``.nc`` path.
    config
        The sub-config that produced ``ds`` (stored as ``config_json``).
    key
        The SeedSequence spawn key used (``None`` for deterministic outputs).
    title
        A one-line description of the dataset (global ``title`` attribute).

    Raises
    ------
    ValueError
        If a variable lacks ``units`` or ``long_name``.
    """
    _check_attrs(ds)
    ds = _split_complex(ds)
    ds.attrs = {**ds.attrs, "title": title, "Conventions": "CF-1.10", **provenance(config, key)}
    encoding = {
        name: {"zlib": True, "complevel": 4}
        for name in ds.data_vars
        if ds[name].dtype.kind in "fiub" and ds[name].ndim > 0
    }
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine=ENGINE, encoding=encoding, invalid_netcdf=False)


def read_dataset(path: str | os.PathLike[str]) -> xr.Dataset:
    """Read a dataset written by :func:`write_dataset`, rejoining complex variables."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        ds = ds.load()
    for name in list(ds.data_vars):
        if name in ds and ds[name].attrs.get("complex_part") == "real":
            base = name[: -len("_real")]
            attrs = {k: v for k, v in ds[name].attrs.items() if k != "complex_part"}
            attrs["long_name"] = attrs["long_name"].removesuffix(" (real part)")
            ds[base] = ds[name] + 1j * ds[f"{base}_imag"]
            ds[base].attrs = attrs
            ds = ds.drop_vars([name, f"{base}_imag"])
    return ds


def config_of(ds: xr.Dataset) -> dict[str, Any]:
    """The sub-config stored in a dataset's provenance."""
    return json.loads(ds.attrs["config_json"])
