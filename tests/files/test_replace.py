"""Writing a file whole or not at all (pinrate.files.replace): a write that fails leaves the
old file and no temporary one, every failure of the disk an InputError naming the file."""

from __future__ import annotations

import errno
import io
import os
import stat
from pathlib import Path

import pytest

import pinrate
from pinrate.files import replace_file


def test_a_write_that_fails_part_way_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    path = tmp_path / "kept.txt"
    path.write_bytes(b"the old content")

    def fails(stream: io.BufferedWriter) -> None:
        stream.write(b"x" * 100_000)
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(pinrate.InputError, match=r"kept\.txt.*No space left on device") as refused:
        replace_file(path, "test file", fails)
    assert isinstance(refused.value.__cause__, OSError)
    assert path.read_bytes() == b"the old content" and os.listdir(tmp_path) == ["kept.txt"]


@pytest.mark.parametrize("error", [ValueError("a bug"), KeyboardInterrupt()])
def test_any_other_failure_goes_up_as_it_is_and_leaves_the_old_file(tmp_path: Path, error: BaseException) -> None:
    path = tmp_path / "kept.txt"
    path.write_bytes(b"the old content")

    def fails(stream: io.BufferedWriter) -> None:
        stream.write(b"partial")
        raise error

    with pytest.raises(type(error)):
        replace_file(path, "test file", fails)
    assert path.read_bytes() == b"the old content" and os.listdir(tmp_path) == ["kept.txt"]


def test_a_file_is_replaced_whole_keeping_its_mode_and_a_link_is_followed(tmp_path: Path) -> None:
    real = tmp_path / "real.txt"
    real.write_text("old")
    real.chmod(0o640)
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    assert replace_file(link, "test file", lambda stream: stream.write("new"), encoding="utf-8") == link
    assert link.is_symlink() and real.read_text() == "new"
    assert stat.S_IMODE(real.stat().st_mode) == 0o640
    assert sorted(os.listdir(tmp_path)) == ["link.txt", "real.txt"]
    fresh = replace_file(tmp_path / "fresh.bin", "test file", lambda stream: stream.write(b"\x00\x01"))
    assert fresh.read_bytes() == b"\x00\x01"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o666 & ~umask


def test_what_is_not_a_regular_file_is_not_written_over(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(pinrate.InputError, match="not a regular file"):
        replace_file(fifo, "test file", lambda stream: stream.write(b"x"))
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    with pytest.raises(pinrate.InputError, match="folder"):
        replace_file(tmp_path, "test file", lambda stream: stream.write(b"x"))
    with pytest.raises(pinrate.InputError, match="does not exist"):
        replace_file(tmp_path / "missing" / "file", "test file", lambda stream: stream.write(b"x"))
