"""The console's saving of recorded runs (pinrate.teleop.actions.Recordings): whole files
only, and a run whose replay cannot be written is still saved, served and said."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pinrate import InputError, Teleop
from pinrate.teleop import Recording
from pinrate.teleop.actions import Recordings


class FailingViewer:
    """A viewer whose replay page cannot be written (a full disk, as replace_file says it)."""

    def save_replay(self, path: Path, configurations: np.ndarray, *, fps: float) -> Path:
        raise InputError(
            f"replay file {str(path)!r} could not be written (No space left on device); nothing was written"
        )


def test_a_run_whose_replay_fails_is_still_saved_served_and_said(ur5, tmp_path: Path) -> None:
    teleop = Teleop(ur5, dt=0.01)
    teleop.start_recording()
    for k in range(5):
        teleop.command((1, 0, 0), (0, 0, 0), now=k * 0.01)
        teleop.tick(k * 0.01)
    recording = teleop.stop_recording()
    said: list[tuple[tuple[object, ...], dict[str, object]]] = []
    recordings = Recordings(
        tmp_path, robot="ur5", viewer=FailingViewer(), token=None, say=lambda *a, **k: said.append((a, k))
    )
    recordings.save(recording)
    (data,) = recordings.saved
    assert data.suffix == ".npz" and recordings.served == {data.name: data}
    assert len(Recording.load(data)) == len(recording)
    (text, level), options = said[-1]
    assert level == "error" and data.name in text and "No space left on device" in text
    assert options["links"] == [recordings.link(data.name)]
    assert os.listdir(tmp_path) == [data.name]  # no page, no temporary file
