"""Input text files in; results to and from HDF5 (netCDF-4 layout, readable by xarray and h5py)."""
from __future__ import annotations

import os
import stat
from pathlib import Path

import xarray as xr

from .errors import HalfslipInputError, excerpt

ENGINE = "h5netcdf"

PATH_CHARS = 160
"""Most characters of a file path quoted in an error (paths come from the input too)."""

_CHUNK = 1 << 20


def read_input_text(path: str | os.PathLike, what: str, limit: int, *, field: str | None = None) -> str:
    """The UTF-8 text of an input file (scene, sweep, table, profile), read within limits.

    Every file halfslip reads as input comes through here. It refuses, each
    with a one-line :class:`HalfslipInputError` and before reading more than
    ``limit + 1`` bytes: a missing file, anything that is not a regular file
    (a directory, a FIFO, ``/dev/zero``: checked with ``os.stat`` before the
    file is opened, and opened non-blocking and checked again, so nothing can
    make it wait), a file larger than `limit` bytes, text that is not UTF-8,
    and NUL characters.

    Parameters
    ----------
    path : path
        The file.
    what : str
        What the file is ("scene", "sweep", "table", "profile"), for messages.
    limit : int
        Most bytes accepted (a constant of :mod:`halfslip.limits`).
    field : str, optional
        Field of the scene or sweep file that named this file. When given,
        errors about the file as a whole (missing, not a file, too large) are
        located at that field and name the file in the message, and errors
        inside the file (bad UTF-8, NUL) name the file, its line and `field`.
        Without it, every error names the file itself.

    Returns
    -------
    str
    """
    path = Path(path)
    quoted = excerpt(str(path), PATH_CHARS)

    def whole(reason: str) -> HalfslipInputError:
        if field is None:
            return HalfslipInputError(reason, file=str(path))
        return HalfslipInputError(f"{what} file {quoted}: {reason}", field=field)

    def regular(mode: int) -> None:
        if stat.S_ISDIR(mode):
            raise whole(f"is a directory, not a {what} file")
        if not stat.S_ISREG(mode):
            raise whole(f"is not a regular file ({_file_kind(mode)}); give the path of a {what} file")

    try:
        regular(os.stat(path).st_mode)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise whole("no such file" if field is None else "not found") from None
    except OSError as error:
        raise whole(f"cannot read: {error.strerror or error}") from None
    try:
        regular(os.fstat(fd).st_mode)  # the path may have been replaced since the stat
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, min(_CHUNK, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as error:
        raise whole(f"cannot read: {error.strerror or error}") from None
    finally:
        os.close(fd)
    if size > limit:
        raise whole(f"is larger than {limit:,} bytes, the most read for a {what} file "
                    f"(halfslip.limits, docs/interface.md \"Limits\")")
    data = b"".join(chunks)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise HalfslipInputError(
            f"is not UTF-8 text (byte 0x{data[error.start]:02x} at column {_column(data, error.start)})",
            file=str(path), line=data.count(b"\n", 0, error.start) + 1, field=field,
        ) from None
    nul = text.find("\0")
    if nul >= 0:
        raise HalfslipInputError(
            "contains a NUL character (a binary file?)", file=str(path), line=text.count("\n", 0, nul) + 1,
            field=field,
        )
    return text


def _column(data: bytes, index: int) -> int:
    """1-based column of byte `index` in its line."""
    return index - (data.rfind(b"\n", 0, index) + 1) + 1


def _file_kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a plain file"


def write_result(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a result dataset to ``path`` atomically (temporary file, then rename).

    A reader never sees a half-written file, and an existing file is replaced
    only once the new one is complete.
    """
    return write_run(ds, path)


def read_result(path: str | os.PathLike) -> xr.Dataset:
    """Open a result file fully into memory (the file is closed on return)."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()


# -- checkpoints: the solver state of an unfinished run ----------------------
#
# A state is a tree of halfslip dataclasses / named tuples / enums, tuples,
# numbers, strings, None and numpy arrays. It is written as a JSON description
# (floats by repr, hence exact) plus one netCDF variable per array. Decoding
# instantiates only classes of the halfslip package (no arbitrary objects).

CHECKPOINT_GROUP = "checkpoint"


def encode_tree(obj, arrays: list) -> object:
    """JSON-able description of ``obj``; arrays are appended to ``arrays``."""
    import dataclasses as dc
    import enum

    import numpy as np

    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, enum.Enum):
        return {"__enum__": _qualname(obj), "value": obj.value}
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return {"__float__": repr(float(obj))}
    if isinstance(obj, np.ndarray):
        arrays.append(obj)
        return {"__array__": len(arrays) - 1, "dtype": obj.dtype.str, "readonly": not obj.flags.writeable}
    if dc.is_dataclass(obj) and not isinstance(obj, type):
        return {"__dataclass__": _qualname(obj),
                "fields": {f.name: encode_tree(getattr(obj, f.name), arrays) for f in dc.fields(obj)}}
    if isinstance(obj, tuple) and hasattr(obj, "_fields"):
        return {"__namedtuple__": _qualname(obj), "items": [encode_tree(v, arrays) for v in obj]}
    if isinstance(obj, (tuple, list)):
        return {"__tuple__" if isinstance(obj, tuple) else "__list__": [encode_tree(v, arrays) for v in obj]}
    if isinstance(obj, dict):
        return {"__dict__": [[encode_tree(k, arrays), encode_tree(v, arrays)] for k, v in obj.items()]}
    raise TypeError(f"cannot checkpoint an object of type {type(obj).__name__}")


def decode_tree(node, arrays: list):
    """Inverse of :func:`encode_tree`."""
    import numpy as np

    if node is None or isinstance(node, (bool, str, int)):
        return node
    if "__float__" in node:
        return float(node["__float__"])
    if "__array__" in node:
        a = np.array(arrays[node["__array__"]], dtype=np.dtype(node["dtype"]))
        if node["readonly"]:
            a.flags.writeable = False
        return a
    if "__enum__" in node:
        return _resolve(node["__enum__"])(node["value"])
    if "__dataclass__" in node:
        cls = _resolve(node["__dataclass__"])
        obj = object.__new__(cls)
        for k, v in node["fields"].items():
            object.__setattr__(obj, k, decode_tree(v, arrays))
        return obj
    if "__namedtuple__" in node:
        return _resolve(node["__namedtuple__"])(*[decode_tree(v, arrays) for v in node["items"]])
    if "__tuple__" in node:
        return tuple(decode_tree(v, arrays) for v in node["__tuple__"])
    if "__list__" in node:
        return [decode_tree(v, arrays) for v in node["__list__"]]
    if "__dict__" in node:
        return {decode_tree(k, arrays): decode_tree(v, arrays) for k, v in node["__dict__"]}
    raise ValueError("not a halfslip checkpoint node")


def _qualname(obj) -> str:
    cls = type(obj)
    return f"{cls.__module__}:{cls.__qualname__}"


def _resolve(name: str):
    import importlib

    module, _, qualname = name.partition(":")
    if module != "halfslip" and not module.startswith("halfslip."):
        raise ValueError(f"checkpoint names a class outside halfslip: {name}")
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def checkpoint_dataset(tree) -> xr.Dataset:
    """Encode a checkpoint tree as a small Dataset (arrays + JSON)."""
    import json

    import numpy as np

    arrays: list = []
    description = encode_tree(tree, arrays)
    data = {}
    for k, a in enumerate(arrays):
        stored = a.astype(np.int8) if a.dtype == bool else a
        data[f"a{k}"] = (tuple(f"a{k}_{d}" for d in range(a.ndim)), stored)
    return xr.Dataset(data, attrs={"tree": json.dumps(description)})


def read_checkpoint(path: str | os.PathLike):
    """The checkpoint tree of an unfinished run file, or None when it has none."""
    import json

    import h5py

    with h5py.File(path, "r") as f:
        if CHECKPOINT_GROUP not in f:
            return None
        group = f[CHECKPOINT_GROUP]
        description = json.loads(group.attrs["tree"])
        n = sum(1 for k in group if k.startswith("a") and k[1:].isdigit())
        arrays = [group[f"a{k}"][()] for k in range(n)]
    return decode_tree(description, arrays)


def write_run(ds: xr.Dataset, path: str | os.PathLike, checkpoint=None) -> Path:
    """Write a run atomically, with the checkpoint of an unfinished run when given."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.partial")
    encoding = {k: {"zlib": True, "complevel": 1} for k in ds.data_vars if ds[k].ndim == 2}
    ds.to_netcdf(tmp, engine=ENGINE, encoding=encoding)
    if checkpoint is not None:
        checkpoint_dataset(checkpoint).to_netcdf(tmp, mode="a", group=CHECKPOINT_GROUP, engine=ENGINE)
    os.replace(tmp, path)
    return path


class RunFileWriter:
    """Writes a run's file from time to time while it marches.

    Each write replaces the file atomically with every stored step so far and
    the checkpoint needed to resume; the interval adapts so that writing costs
    at most about a fifth of the run time.

    Parameters
    ----------
    path : path-like
    min_interval : float
        Seconds between writes at least.
    """

    def __init__(self, path: str | os.PathLike, min_interval: float = 2.0):
        import time

        self.path = Path(path)
        self.min_interval = float(min_interval)
        self.interval = self.min_interval
        self._clock = time.perf_counter
        self.last = self._clock()
        self.writes = 0

    def due(self) -> bool:
        return self._clock() - self.last >= self.interval

    def write(self, ds: xr.Dataset, checkpoint=None) -> None:
        started = self._clock()
        write_run(ds, self.path, checkpoint)
        took = self._clock() - started
        self.last = self._clock()
        self.interval = max(self.min_interval, 5.0 * took)
        self.writes += 1
