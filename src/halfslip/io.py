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
    """Open a result file fully into memory (the file is closed on return).

    The file is inspected first (:func:`check_result_file`): a file handed to
    halfslip can make it read numbers and text only, within RESULT_LIMITS.
    """
    check_result_file(path)
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return upgrade_result(ds.load())


def upgrade_result(ds: xr.Dataset) -> xr.Dataset:
    """A result written by an older halfslip, with today's names.

    ``shift`` (hidden by ``Dataset.shift``) is ``rigid_shift`` since 0.2.
    """
    if "shift" in ds.data_vars and "rigid_shift" not in ds.variables and ds["shift"].dims == ("t",):
        ds = ds.rename_vars(shift="rigid_shift")
    return ds


#: Caps on a result file read back (``--resume``, ``plot``, a sweep continued). A run stores at
#: most output.points x stored steps numbers per field; 2**27 numbers (1 GiB as float64) is over
#: any result a scene within the scene limits writes, and under the memory of a small machine.
RESULT_LIMITS = {
    "elements": 2**27,         # numbers in all datasets together
    "objects": 100_000,        # groups, datasets and links
    "attribute_bytes": 2**24,  # one attribute (the scene text is the largest, a few kB)
}


def check_result_file(path: str | os.PathLike) -> None:
    """Refuse an HDF5 file that is not plain data of bounded size.

    Walks every link of the file before any data is read: external and soft
    links, external or virtual storage, reference, compound and opaque dataset
    types are refused, as are sizes over RESULT_LIMITS.

    Raises
    ------
    UnsafeFileError
        With what is wrong (the caller names the file).
    """
    import h5py

    with h5py.File(path, "r") as f:
        seen = {"objects": 0, "elements": 0}
        stack = [f]
        while stack:
            group = stack.pop()
            _check_attributes(group)
            for name in group:
                seen["objects"] += 1
                if seen["objects"] > RESULT_LIMITS["objects"]:
                    raise UnsafeFileError(f"it holds more than {RESULT_LIMITS['objects']} objects")
                if not isinstance(group.get(name, getlink=True), h5py.HardLink):
                    raise UnsafeFileError(f"{excerpt(name)} is a link to elsewhere")
                obj = group[name]
                if isinstance(obj, h5py.Group):
                    stack.append(obj)
                    continue
                if not isinstance(obj, h5py.Dataset) or obj.is_virtual or obj.external:
                    raise UnsafeFileError(f"{excerpt(name)} is not a plain dataset of this file")
                kind = obj.dtype.kind
                if not (kind in _ARRAY_KINDS or h5py.check_string_dtype(obj.dtype) is not None):
                    raise UnsafeFileError(f"{excerpt(name)} holds {obj.dtype}, neither numbers nor text")
                seen["elements"] += int(obj.size)
                if seen["elements"] > RESULT_LIMITS["elements"]:
                    raise UnsafeFileError(f"its datasets hold more than {RESULT_LIMITS['elements']} numbers")
                _check_attributes(obj)


def _check_attributes(obj) -> None:
    for name in obj.attrs:
        if obj.attrs.get_id(name).get_storage_size() > RESULT_LIMITS["attribute_bytes"]:
            raise UnsafeFileError(f"its attribute {excerpt(name)} is larger than {RESULT_LIMITS['attribute_bytes']} bytes")


# -- checkpoints: the solver state of an unfinished run ----------------------
#
# A checkpoint is pure data. Its tree holds numbers, strings, None, lists,
# tuples, dicts keyed by strings or integers, numeric arrays and *records*: instances of a
# fixed, versioned set of halfslip classes (RECORD_KINDS), named in the file by
# a short kind name, never by a module path. Decoding looks kind names up in
# that table and nothing else, so no name in a file can reach a callable; every
# record's field names must be exactly those of its class. The tree is JSON in
# the attribute ``tree`` of the group ``checkpoint``, with the format version in
# ``format``; each array is a dataset ``a<k>`` of that group. Sizes are capped
# (CHECKPOINT_LIMITS) before anything is read. docs/interface.md has the format.

CHECKPOINT_GROUP = "checkpoint"
#: Version of the checkpoint format; a file of another version is refused (finish it with the
#: halfslip that wrote it, or run again).
CHECKPOINT_FORMAT = "halfslip-checkpoint-2"


class UnsafeFileError(ValueError):
    """A file handed to halfslip that is not plain, bounded data of the form halfslip writes."""


class CheckpointError(UnsafeFileError):
    """A checkpoint that is not one this version of halfslip writes."""


#: Caps on what a checkpoint may hold, checked before it is read. The largest checkpoint a run
#: writes is the exact method's level memory, at most 4 numbers per step of the history (at most
#: 2e7 steps, scene limit): 8e7 numbers, stored as arrays; the general solver's memory is a few
#: thousand points. The JSON tree stays small because long float sequences go to arrays.
CHECKPOINT_LIMITS = {
    "tree_bytes": 16 * 2**20,     # the JSON description (a few kB in practice)
    "depth": 32,                  # nesting of the tree (6 in practice)
    "nodes": 1_000_000,           # entries of the tree (a few hundred in practice)
    "arrays": 10_000,             # datasets in the group (tens in practice)
    "elements": 2**27,            # numbers in all arrays together (1 GiB as float64)
}

_ARRAY_KINDS = "biuf"  # bool, signed and unsigned integers, floats: numbers only


def _record_kinds() -> dict:
    """The record kinds a checkpoint may hold: kind name -> class (dataclass or named tuple)."""
    from .geometry import NormalSolution, _ContactPressure
    from .solvers.exact import LevelMemory
    from .solvers._windows import EdgeWindow
    from .solvers.general import GeneralMemory
    from .state import ContactState, Loads

    classes = (ContactState, Loads, NormalSolution, _ContactPressure, LevelMemory, GeneralMemory, EdgeWindow)
    return {cls.__name__.lstrip("_"): cls for cls in classes}


def encode_tree(obj, arrays: list, kinds: dict | None = None) -> object:
    """JSON-able description of ``obj``; arrays are appended to ``arrays``.

    Raises
    ------
    TypeError
        For an object that is not pure data or a record of ``RECORD_KINDS``:
        a run must never write what it could not read back.
    """
    import dataclasses as dc

    import numpy as np

    if kinds is None:
        kinds = {cls: name for name, cls in _record_kinds().items()}
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, np.bool_):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return {"float": repr(float(obj))}
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _ARRAY_KINDS:
            raise TypeError(f"cannot checkpoint an array of dtype {obj.dtype}")
        arrays.append(obj)
        return {"array": len(arrays) - 1, "dtype": obj.dtype.str, "readonly": not obj.flags.writeable}
    kind = kinds.get(type(obj))
    if kind is not None:
        if dc.is_dataclass(obj):
            return {"record": kind, "fields": {f.name: encode_tree(getattr(obj, f.name), arrays, kinds)
                                               for f in dc.fields(obj)}}
        return {"record": kind, "items": [encode_tree(v, arrays, kinds) for v in obj]}
    if type(obj) in (tuple, list) and len(obj) > 8 and all(type(v) is float for v in obj):
        arrays.append(np.array(obj, dtype=float))  # a long sequence of floats: one array, exact
        return {"floats": len(arrays) - 1, "as": "tuple" if isinstance(obj, tuple) else "list"}
    if type(obj) in (tuple, list):
        return {"tuple" if isinstance(obj, tuple) else "list": [encode_tree(v, arrays, kinds) for v in obj]}
    if type(obj) is dict and all(type(k) in (str, int) for k in obj):
        return {"dict": [[k, encode_tree(v, arrays, kinds)] for k, v in obj.items()]}
    raise TypeError(f"cannot checkpoint an object of type {type(obj).__name__}")


def decode_tree(node, arrays: list, kinds: dict | None = None, depth: int = 0):
    """Inverse of :func:`encode_tree`; raises CheckpointError for anything it did not write."""
    import dataclasses as dc

    import numpy as np

    if kinds is None:
        kinds = _record_kinds()
    if depth > CHECKPOINT_LIMITS["depth"]:
        raise CheckpointError(f"the checkpoint is nested deeper than {CHECKPOINT_LIMITS['depth']} levels")
    if node is None or isinstance(node, (bool, str)):
        return node
    if isinstance(node, int):
        if abs(node) > 2**63:
            raise CheckpointError("an integer of the checkpoint is out of range")
        return node
    if not isinstance(node, dict) or len(node) not in (1, 2, 3):
        raise CheckpointError("not a halfslip checkpoint node")
    inner = depth + 1
    if set(node) == {"float"} and isinstance(node["float"], str) and len(node["float"]) <= 32:
        try:
            return float(node["float"])
        except ValueError:
            raise CheckpointError("a number of the checkpoint is not a number") from None
    if set(node) == {"array", "dtype", "readonly"}:
        index, dtype = node["array"], node["dtype"]
        if not (isinstance(index, int) and 0 <= index < len(arrays) and isinstance(dtype, str)
                and len(dtype) <= 8 and isinstance(node["readonly"], bool)):
            raise CheckpointError("an array entry of the checkpoint is malformed")
        try:
            dtype = np.dtype(dtype)
        except TypeError:
            raise CheckpointError("an array of the checkpoint has an unknown dtype") from None
        if dtype.kind not in _ARRAY_KINDS:
            raise CheckpointError(f"an array of the checkpoint has dtype {dtype}, not a number type")
        a = np.array(arrays[index], dtype=dtype)
        a.flags.writeable = not node["readonly"]
        return a
    if set(node) == {"floats", "as"} and node["as"] in ("tuple", "list"):
        index = node["floats"]
        if not (isinstance(index, int) and 0 <= index < len(arrays) and arrays[index].ndim == 1):
            raise CheckpointError("a sequence entry of the checkpoint is malformed")
        values = [float(v) for v in np.asarray(arrays[index], dtype=float)]
        return tuple(values) if node["as"] == "tuple" else values
    if set(node) == {"tuple"} and isinstance(node["tuple"], list):
        return tuple(decode_tree(v, arrays, kinds, inner) for v in node["tuple"])
    if set(node) == {"list"} and isinstance(node["list"], list):
        return [decode_tree(v, arrays, kinds, inner) for v in node["list"]]
    if set(node) == {"dict"} and isinstance(node["dict"], list):
        out = {}
        for pair in node["dict"]:
            if not (isinstance(pair, list) and len(pair) == 2 and type(pair[0]) in (str, int)):
                raise CheckpointError("a mapping of the checkpoint has a key that is neither text nor an integer")
            out[pair[0]] = decode_tree(pair[1], arrays, kinds, inner)
        return out
    if "record" in node and len(node) == 2:
        cls = kinds.get(node["record"]) if isinstance(node["record"], str) else None
        if cls is None:
            raise CheckpointError(f"the checkpoint names an unknown record kind {excerpt(node['record'])}")
        if dc.is_dataclass(cls):
            fields = node.get("fields")
            names = [f.name for f in dc.fields(cls)]
            # a field added since the checkpoint was written (with a default: GeneralMemory.windows, 0.4.5)
            defaults = {f.name: f.default for f in dc.fields(cls) if f.default is not dc.MISSING}
            if not (isinstance(fields, dict) and set(fields) <= set(names) and set(names) - set(fields) <= set(defaults)):
                raise CheckpointError(f"a {node['record']} record of the checkpoint has other fields than {names}")
            obj = object.__new__(cls)
            for name in names:
                value = decode_tree(fields[name], arrays, kinds, inner) if name in fields else defaults[name]
                object.__setattr__(obj, name, value)
            return obj
        items = node.get("items")
        if not isinstance(items, list) or len(items) != len(cls._fields):
            raise CheckpointError(f"a {node['record']} record of the checkpoint has the wrong number of items")
        return cls(*(decode_tree(v, arrays, kinds, inner) for v in items))
    raise CheckpointError("not a halfslip checkpoint node")


def _add_checkpoint(h5file, tree) -> None:
    """Write ``tree`` into the open h5py file as the group ``checkpoint``."""
    import json

    import numpy as np

    arrays: list = []
    description = encode_tree(tree, arrays)
    group = h5file.create_group(CHECKPOINT_GROUP)
    group.attrs["format"] = CHECKPOINT_FORMAT
    group.attrs["tree"] = json.dumps(description)
    for k, a in enumerate(arrays):
        group.create_dataset(f"a{k}", data=a.astype(np.int8) if a.dtype == bool else a)


def read_checkpoint(path: str | os.PathLike):
    """The checkpoint tree of an unfinished run file, or None when it has none.

    Only pure data is read: see the module notes. Every size is checked against
    CHECKPOINT_LIMITS before the data are read.

    Raises
    ------
    CheckpointError
        For anything that is not a checkpoint of this format.
    """
    import json

    import h5py

    with h5py.File(path, "r") as f:
        link = f.get(CHECKPOINT_GROUP, getlink=True)
        if link is None:
            return None
        if not isinstance(link, h5py.HardLink) or not isinstance(f[CHECKPOINT_GROUP], h5py.Group):
            raise CheckpointError("the checkpoint is not a group of this file")
        group = f[CHECKPOINT_GROUP]
        if _attribute_text(group, "format") != CHECKPOINT_FORMAT:
            raise CheckpointError(f"the checkpoint is not of format {CHECKPOINT_FORMAT}")
        tree = _attribute_text(group, "tree", CHECKPOINT_LIMITS["tree_bytes"])
        names = list(group)
        if len(names) > CHECKPOINT_LIMITS["arrays"]:
            raise CheckpointError(f"the checkpoint holds more than {CHECKPOINT_LIMITS['arrays']} arrays")
        if sorted(names) != sorted(f"a{k}" for k in range(len(names))):
            raise CheckpointError("the checkpoint's arrays are not named a0, a1, ...")
        datasets = []
        total = 0
        for k in range(len(names)):
            link = group.get(f"a{k}", getlink=True)
            d = group[f"a{k}"] if isinstance(link, h5py.HardLink) else None
            if not isinstance(d, h5py.Dataset) or d.is_virtual or d.external:
                raise CheckpointError(f"array a{k} of the checkpoint is not a plain dataset of this file")
            if d.dtype.kind not in _ARRAY_KINDS or d.dtype.itemsize > 8 or d.ndim > 4:
                raise CheckpointError(f"array a{k} of the checkpoint has dtype {d.dtype}, not a number type")
            total += int(d.size)
            if total > CHECKPOINT_LIMITS["elements"]:
                raise CheckpointError(f"the checkpoint's arrays hold more than {CHECKPOINT_LIMITS['elements']} numbers")
            datasets.append(d)
        arrays = [d[()] for d in datasets]
    try:
        description = json.loads(tree)
        _check_size(description)
        return decode_tree(description, arrays)
    except CheckpointError:
        raise
    except (ValueError, TypeError, RecursionError) as error:  # malformed JSON or structure
        raise CheckpointError(f"the checkpoint is malformed ({type(error).__name__})") from None


def _attribute_text(obj, name: str, limit: int = 256) -> str | None:
    """A string attribute of an HDF5 object, refusing anything else or anything longer than ``limit``."""
    import numpy as np

    if name not in obj.attrs:
        return None
    info = obj.attrs.get_id(name)
    if info.get_storage_size() > limit or info.shape not in ((), None):
        raise CheckpointError(f"the attribute {name!r} is not a short text")
    value = obj.attrs[name]
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) or not isinstance(value, str):
        raise CheckpointError(f"the attribute {name!r} is not text")
    return value


def _check_size(description) -> None:
    """Refuse JSON trees with more nodes or nesting than CHECKPOINT_LIMITS (iteratively)."""
    stack, count = [(description, 0)], 0
    while stack:
        node, depth = stack.pop()
        count += 1
        if count > CHECKPOINT_LIMITS["nodes"] or depth > CHECKPOINT_LIMITS["depth"]:
            raise CheckpointError("the checkpoint is larger or deeper than a run writes")
        if isinstance(node, dict):
            stack.extend((v, depth + 1) for v in node.values())
        elif isinstance(node, list):
            stack.extend((v, depth + 1) for v in node)


# -- writing result files -----------------------------------------------------
#
# A result is serialised in memory and then written to a temporary file with a
# unique name next to the target, synced and renamed over it: a reader never
# sees a half-written file, two writers never share a temporary, and the
# temporary exists only for the moment of the byte copy (a run killed then
# leaves it behind; the next run on the same output removes it).

_TEMP_SUFFIX = ".partial"

CONVENTIONS = "CF-1.10"
"""The ``Conventions`` attribute of every file halfslip writes."""


def _encode(ds: xr.Dataset, checkpoint=None) -> bytes:
    import io as _io

    import h5py

    encoding = {k: {"zlib": True, "complevel": 1} for k in ds.data_vars if ds[k].ndim == 2}
    # CF: coordinates have no missing values, so no _FillValue (xarray adds NaN to floats otherwise)
    encoding.update({k: {"_FillValue": None} for k in ds.coords})
    if "Conventions" not in ds.attrs:
        ds = ds.assign_attrs(Conventions=CONVENTIONS)
    image = _io.BytesIO(bytes(ds.to_netcdf(engine=ENGINE, encoding=encoding)))
    if checkpoint is not None:
        with h5py.File(image, "a") as f:
            _add_checkpoint(f, checkpoint)
    return image.getvalue()


def write_run(ds: xr.Dataset, path: str | os.PathLike, checkpoint=None) -> Path:
    """Write a run atomically, with the checkpoint of an unfinished run when given."""
    path = Path(path)
    data = _encode(ds, checkpoint)
    _replace_with(path, data)
    return path


def _replace_with(path: Path, data: bytes) -> None:
    import tempfile

    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=_TEMP_SUFFIX, dir=path.parent)
    _WRITING.add(tmp)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # as the file a plain open() would create (mkstemp makes 0o600)
        os.replace(tmp, path)
    except BaseException:
        remove_temporaries_being_written()
        raise
    finally:
        _WRITING.discard(tmp)


#: Temporaries this process is writing now (at most one): what an immediate exit removes.
_WRITING: set = set()


def remove_temporaries_being_written() -> None:
    """Remove the temporary files this process is writing (before an immediate exit)."""
    for tmp in list(_WRITING):
        try:
            os.unlink(tmp)
        except OSError:
            pass


def remove_stale_temporaries(path: str | os.PathLike) -> int:
    """Remove the temporaries of earlier, killed writers of ``path``; call while holding its lock."""
    path = Path(path)
    removed = 0
    import glob

    for stale in path.parent.glob(f".{glob.escape(path.name)}.*{_TEMP_SUFFIX}"):
        try:
            stale.unlink()
            removed += 1
        except OSError:
            pass
    return removed


# -- output locations -----------------------------------------------------------

#: The attribute every halfslip result file carries (runs, sweeps and steady states).
RESULT_MARKER = "halfslip_version"
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def is_halfslip_result(path: str | os.PathLike) -> bool:
    """Whether ``path`` is an HDF5 file that halfslip wrote (it has the marker attribute)."""
    import h5py

    try:
        with open(path, "rb") as f:
            if f.read(8) != _HDF5_SIGNATURE:
                return False
        with h5py.File(path, "r") as f:
            return RESULT_MARKER in f.attrs
    except (OSError, ValueError):
        return False


def check_output(path: str | os.PathLike, *, inputs=(), overwrite: bool = False, option: str = "-o") -> Path:
    """Check, before any computation, that a result can be written to ``path``.

    Refused: a folder, a missing or unwritable folder, any of ``inputs`` (the
    scene and the files it reads), and an existing file that is not a halfslip
    result unless ``overwrite``. A temporary file is created and removed in the
    folder to prove it writable.

    Raises
    ------
    HalfslipInputError
    """
    import tempfile

    from .errors import HalfslipInputError

    path = Path(path)
    where = str(path)
    if path.is_dir():
        raise HalfslipInputError("is a folder; name a file such as OUT.h5", file=where, field=option)
    folder = path.parent
    if not folder.is_dir():
        raise HalfslipInputError(f"the folder {excerpt(folder, PATH_CHARS)} does not exist", file=where, field=option)
    for source in inputs:
        if source is not None and same_file(path, Path(source)):
            raise HalfslipInputError(f"is an input of this run ({excerpt(source, PATH_CHARS)}); name another file",
                                     file=where, field=option)
    if path.exists() or path.is_symlink():
        if not path.is_file():
            raise HalfslipInputError("exists and is not a regular file", file=where, field=option)
        if not overwrite and not is_halfslip_result(path):
            raise HalfslipInputError("exists and is not a halfslip result; remove it or add --overwrite",
                                     file=where, field=option)
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=_TEMP_SUFFIX, dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as error:
        raise HalfslipInputError(f"cannot write in its folder ({error.strerror or type(error).__name__})",
                                 file=where, field=option) from None
    return path


def same_file(a: Path, b: Path) -> bool:
    """Whether two paths name the same file (or would, once created)."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except OSError:
        return False


class OutputLock:
    """Exclusive right to write one output file, for the life of a command.

    On Linux an abstract Unix socket named after the file's real path: released
    by the kernel when the process ends however it ends, and leaves nothing on
    disk. Elsewhere an ``flock`` on ``.NAME.lock`` beside the file, removed on
    release.

    Raises
    ------
    HalfslipInputError
        When another halfslip process holds it.
    """

    def __init__(self, path: str | os.PathLike, option: str = "-o"):
        self.path = Path(path)
        self.option = option
        self._socket = None
        self._file = None
        self._lockfile = None

    def __enter__(self) -> "OutputLock":
        import hashlib
        import socket
        import sys

        from .errors import HalfslipInputError

        key = hashlib.sha256(str(self.path.parent.resolve() / self.path.name).encode()).hexdigest()[:40]
        busy = HalfslipInputError("another halfslip process is writing this file; wait for it or name another",
                                  file=str(self.path), field=self.option)
        if sys.platform.startswith("linux"):
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                sock.bind(f"\0halfslip-output-{key}")
            except OSError:
                sock.close()
                raise busy from None
            self._socket = sock
        else:
            import fcntl

            self._lockfile = self.path.with_name(f".{self.path.name}.lock")
            self._file = open(self._lockfile, "a")
            try:
                fcntl.flock(self._file, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                self._file.close()
                self._file = None
                raise busy from None
        remove_stale_temporaries(self.path)
        return self

    def __exit__(self, *exc) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None
        if self._file is not None:
            try:
                os.unlink(self._lockfile)
            except OSError:
                pass
            self._file.close()
            self._file = None


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
