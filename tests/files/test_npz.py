"""Reading a saved .npz without trust (pinrate.files.npz, over pinrate.files.npz_members):
read only after every header is checked, every failure an InputError naming the file."""

from __future__ import annotations

import pathlib
import pickle
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.files import DEFLATE_RATIO, MAX_MEMBERS, open_npz
from support import load_with_timeout, npy, raw_zip, special_files


def members(path: Path, **fields: np.ndarray) -> Path:
    """An .npz numpy writes, of ``fields`` (uncompressed)."""
    np.savez(path, **fields)
    return path


def read_all(path: Path, *, max_bytes: int | None = None) -> dict[str, np.ndarray]:
    options = {} if max_bytes is None else {"max_bytes": max_bytes}
    with open_npz(path, "test file", **options) as npz:
        return {name: npz.array(name) for name in npz.members}


def test_arrays_read_back_as_numpy_wrote_them(tmp_path: Path) -> None:
    fields = {
        "floats": np.arange(12.0).reshape(3, 4),
        "fortran": np.asfortranarray(np.arange(6.0).reshape(2, 3)),
        "big_endian": np.arange(5, dtype=">i4"),
        "text": np.array(["moving", "at a joint limit", "ü"]),
        "flag": np.array(True),
        "empty": np.zeros((0, 6)),
        "scalar": np.array(0.25),
    }
    for writer in (np.savez, np.savez_compressed):
        path = tmp_path / f"{writer.__name__}.npz"
        writer(path, **fields)
        read = read_all(path)
        assert read.keys() == fields.keys()
        for name, value in fields.items():
            assert read[name].shape == value.shape and read[name].dtype.isnative, name
            np.testing.assert_array_equal(read[name], value)


def test_an_object_array_is_refused_and_never_unpickled(tmp_path: Path) -> None:
    """An object array is a pickle: reading it would run whatever it names (here, create a
    file). It is refused from its header and nothing is run."""
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self) -> tuple[object, tuple[object, ...]]:
            return (pathlib.Path.touch, (pathlib.Path(marker),))

    assert pickle.loads(pickle.dumps(Payload())) is None and marker.exists()  # what it would do
    marker.unlink()
    path = members(tmp_path / "pickle.npz", data=np.array([Payload()], dtype=object))
    with pytest.raises(pinrate.InputError, match=r"pickle\.npz.*field 'data'.*not booleans"):
        read_all(path)
    assert not marker.exists()


def test_headers_that_lie_or_overreach_are_refused_unread(tmp_path: Path) -> None:
    floats = npy((4,), "<f8", bytes(32))
    header = b"{'descr': '<f8', 'fortran_order': False, 'shape': (4L,), }".ljust(117) + b"\n"
    python_2 = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header  # numpy would warn and read it
    cases = {
        "shape beyond data": [("q.npy", npy((2**40,), "<f8", bytes(32)), 0, 0, 0)],
        "data beyond shape": [("q.npy", npy((2,), "<f8", bytes(32)), 0, 0, 0)],
        "negative shape": [("q.npy", npy((-4,), "<f8", bytes(32)), 0, 0, 0)],
        "structured dtype": [("q.npy", npy((1,), [("a", "<f8")], bytes(8)), 0, 0, 0)],
        "bytes dtype": [("q.npy", npy((1,), "|S8", bytes(8)), 0, 0, 0)],
        "empty strings": [("q.npy", npy((10**12,), "<U0"), 0, 0, 0)],
        "a python 2 header": [("q.npy", python_2 + bytes(32), 0, 0, 0)],
        "a header of 60 KB": [
            ("q.npy", b"\x93NUMPY\x02\x00" + (60_000).to_bytes(4, "little") + b" " * 60_000, 0, 0, 0)
        ],
        "format 3.0": [("q.npy", b"\x93NUMPY\x03\x00" + floats[8:], 0, 0, 0)],
        "not an .npy": [("q.npy", b"just some bytes", 0, 0, 0)],
        "not named .npy": [("q.txt", floats, 0, 0, 0)],
        "two of a name": [("q.npy", floats, 0, 0, 0), ("q.npy", floats, 0, 0, 0)],
        "bzip2": [("q.npy", floats, 12, 0, 0)],
        "too many members": [(f"f{i}.npy", floats, 0, 0, 0) for i in range(MAX_MEMBERS + 1)],
        "more than deflate holds": [("q.npy", zlib.compress(floats)[2:-4], 8, 0, DEFLATE_RATIO * 100 + 5000)],
    }
    for label, entries in cases.items():
        path = tmp_path / f"{label}.npz"
        path.write_bytes(
            raw_zip(
                [(name, data, method, zlib.crc32(data), size or len(data)) for name, data, method, _, size in entries]
            )
        )
        with pytest.raises(pinrate.InputError) as refused:
            read_all(path)
        assert str(path) in str(refused.value), (label, refused.value)
    encrypted = tmp_path / "encrypted.npz"
    data = bytearray(raw_zip([("q.npy", floats, 0, zlib.crc32(floats), len(floats))]))
    data[6] |= 1  # the local header's flag
    data[data.index(b"PK\x01\x02") + 8] |= 1  # the central directory's
    encrypted.write_bytes(bytes(data))
    with pytest.raises(pinrate.InputError, match="encrypted"):
        read_all(encrypted)


def test_a_checksum_that_does_not_match_is_refused_when_read(tmp_path: Path) -> None:
    floats = npy((4,), "<f8", bytes(32))
    path = tmp_path / "crc.npz"
    path.write_bytes(raw_zip([("q.npy", floats, 0, 12345, len(floats))]))
    with pytest.raises(pinrate.InputError, match=r"crc\.npz.*field 'q'.*CRC"):
        read_all(path)


def test_the_cap_counts_arrays_and_their_strings_before_reading(tmp_path: Path) -> None:
    path = members(tmp_path / "cap.npz", q=np.zeros(100), words=np.array(["ab"] * 10))
    assert read_all(path, max_bytes=800 + 80 + 800)["q"].shape == (100,)
    with pytest.raises(pinrate.InputError, match="max_bytes"):
        read_all(path, max_bytes=800 + 80 + 799)  # each string counts 80 bytes besides its 8
    with open_npz(path, "test file") as npz, pytest.raises(pinrate.InputError, match="max_bytes"):
        npz.reserve(npz.max_bytes)
    for bad in (-1, 1.5, True):
        with pytest.raises(pinrate.InputError, match="max_bytes"):
            open_npz(path, "test file", max_bytes=bad)


def test_only_regular_zip_files_are_opened(tmp_path: Path) -> None:
    for label, path, said in special_files(tmp_path):
        error = load_with_timeout(lambda path: open_npz(path, "test file").close(), path)
        assert isinstance(error, pinrate.InputError) and str(path) in str(error), (label, error)
        assert said.split(":")[0] in str(error), (label, error)
    text = tmp_path / "pickle.npz"
    text.write_bytes(pickle.dumps([1, 2, 3]))
    with pytest.raises(pinrate.InputError, match=r"not an \.npz archive"):
        open_npz(text, "test file")
    with pytest.raises(pinrate.InputError, match="does not exist"):
        open_npz(tmp_path / "missing.npz", "test file")
    zipped = tmp_path / "bad.npz"
    zipped.write_bytes(b"PK\x03\x04" + bytes(100))
    with pytest.raises(pinrate.InputError, match=r"not a readable \.npz archive"):
        open_npz(zipped, "test file")


def test_fields_are_checked_by_kind_and_dimensions(tmp_path: Path) -> None:
    path = members(
        tmp_path / "fields.npz",
        q=np.zeros((2, 3)),
        flag=np.array(True),
        bad_flag=np.array(2, dtype=np.uint8).view(np.bool_),
        names=np.array(["a", ""]),
        dt=np.array(0.5),
        nan=np.array([0.0, np.nan]),
    )
    with open_npz(path, "test file") as npz:
        npz.fields(["q", "flag"], ["bad_flag", "names", "dt", "nan"])
        with pytest.raises(pinrate.InputError, match=r"lacks the field.*missing"):
            npz.fields(["missing", *npz.members])
        with pytest.raises(pinrate.InputError, match=r"unknown field.*'nan'"):
            npz.fields(["q", "flag", "bad_flag", "names", "dt"])
        with pytest.raises(pinrate.InputError, match=r"field 'q' has 2 dimensions \(shape \(2, 3\)\), not 1"):
            npz.floats("q", 1)
        with pytest.raises(pinrate.InputError, match="field 'q' holds floats, not text"):
            npz.texts("q")
        assert npz.flag("flag") is True and npz.number("dt") == 0.5
        with pytest.raises(pinrate.InputError, match="field 'bad_flag' holds the byte 2"):
            npz.flag("bad_flag")
        with pytest.raises(pinrate.InputError, match=r"field 'names' holds the name ''"):
            npz.names("names")
        with pytest.raises(pinrate.InputError, match=r"field 'nan' holds nan at 1"):
            npz.floats("nan", 1)
        with pytest.raises(pinrate.InputError, match=r"field 'nan' holds NaN at 1"):
            npz.floats("nan", 1, finite=False)


def test_a_member_of_a_damaged_zip_is_refused_by_name(tmp_path: Path) -> None:
    path = tmp_path / "short.npz"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("q.npy", npy((1000,), "<f8", np.random.default_rng(0).random(1000).tobytes()))
    data = bytearray(path.read_bytes())
    data[200] ^= 0xFF  # inside the deflated stream
    path.write_bytes(bytes(data))
    with pytest.raises(pinrate.InputError, match=r"short\.npz.*'q'"):
        read_all(path)
