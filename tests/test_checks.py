"""The input checks every entry point shares (pinrate.checks)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.checks import (
    PHYSICAL_BOUND,
    as_rng,
    check_count,
    check_output_file,
    check_output_folder,
    check_positive,
    check_vector,
)


@pytest.mark.parametrize("seed", [-1, -(2**70), True, 1.5, "seven", [1, 2]])
def test_bad_seeds(seed: object) -> None:
    with pytest.raises(pinrate.InputError, match="rng"):
        as_rng(seed)


def test_good_seeds_reproduce() -> None:
    assert as_rng(7).random() == as_rng(np.int64(7)).random()
    generator = np.random.default_rng(1)
    assert as_rng(generator) is generator


@pytest.mark.parametrize("value", [0, -3, 2.0, 1.5, True, "4", None, np.float64(3.0)])
def test_bad_counts(value: object) -> None:
    with pytest.raises(pinrate.InputError, match="samples"):
        check_count(value, "samples", minimum=1)


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf, 2e6, True, "1", None])
def test_bad_positive_numbers(value: object) -> None:
    with pytest.raises(pinrate.InputError, match="gain"):
        check_positive(value, "gain")


def test_positive_numbers_at_the_edges() -> None:
    assert check_positive(PHYSICAL_BOUND, "dt") == PHYSICAL_BOUND
    assert check_positive(math.inf, "speed", allow_inf=True) == math.inf
    assert check_positive(5e-324, "tol") == 5e-324


def test_vectors_name_the_entry_beyond_the_bound() -> None:
    with pytest.raises(pinrate.InputError, match=r"twist\[2\] = 1e\+07"):
        check_vector([0.0, 0.0, 1e7], 3, "twist")
    with pytest.raises(pinrate.InputError, match=r"NaN or inf at q\[1\] \(elbow\)"):
        check_vector([1e300, math.nan], 2, "q", names=["shoulder", "elbow"])
    # Every entry within the bound is fine, however long the vector.
    long = np.full(4, 0.9 * PHYSICAL_BOUND)
    np.testing.assert_array_equal(check_vector(long, 4, "q"), long)


def test_output_folders(tmp_path: Path) -> None:
    created = check_output_folder(tmp_path / "a" / "b", "--out")
    assert created.is_dir()
    file = tmp_path / "file"
    file.write_text("keep me")
    with pytest.raises(pinrate.InputError, match="exists and is not a folder"):
        check_output_folder(file, "--out")
    assert file.read_text() == "keep me"
    with pytest.raises(pinrate.InputError, match="cannot be created"):
        check_output_folder(file / "below", "--out")
    with pytest.raises(pinrate.InputError, match="cannot be created"):  # even for root
        check_output_folder("/proc/pinrate-report", "--out")


def test_output_files(tmp_path: Path) -> None:
    assert check_output_file(tmp_path / "replay.html", "--record") == tmp_path / "replay.html"
    with pytest.raises(pinrate.InputError, match="is a folder"):
        check_output_file(tmp_path, "--record")
    with pytest.raises(pinrate.InputError, match="does not exist"):
        check_output_file(tmp_path / "missing" / "replay.html", "--record")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_unwritable_folders(tmp_path: Path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    with pytest.raises(pinrate.InputError, match="not writable"):
        check_output_folder(locked, "--out")
    with pytest.raises(pinrate.InputError, match="not writable"):
        check_output_file(locked / "replay.html", "--record")
