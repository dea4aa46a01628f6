"""Results to and from HDF5 (netCDF-4 layout, readable by xarray and h5py)."""
from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

ENGINE = "h5netcdf"


def write_result(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a result dataset to ``path`` atomically (temporary file, then rename).

    A reader never sees a half-written file, and an existing file is replaced
    only once the new one is complete.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.partial")
    encoding = {k: {"zlib": True, "complevel": 1} for k in ds.data_vars if ds[k].ndim == 2}
    ds.to_netcdf(tmp, engine=ENGINE, encoding=encoding)
    os.replace(tmp, path)
    return path


def read_result(path: str | os.PathLike) -> xr.Dataset:
    """Open a result file fully into memory (the file is closed on return)."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()
