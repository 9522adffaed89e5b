"""`--plant` and `--actuator` of `pinrate demo` and `pinrate teleop` (pinrate.cli.robot_arguments.make_plant)."""

from __future__ import annotations

import pytest
from PIL import Image

from pinrate.cli import main

pytest.importorskip("mujoco")


def test_demo_on_mujoco_says_the_tracking_error_and_draws_the_rates(tmp_path, capsys):
    plot = tmp_path / "rates.png"
    code = main(["demo", "ur5", "--no-viewer", "--plant", "mujoco", "--algorithm", "exact", "--plot", str(plot)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "plant      MuJoCo" in out and "velocity servos" in out
    assert "tracking   tip" in out and "actuators saturated on" in out
    with Image.open(plot) as image:  # a real PNG of the run, not an empty file
        darkest, brightest = image.convert("L").getextrema()
        assert image.size[0] > 400 and brightest - darkest > 100


def test_demo_on_position_servos_converges(capsys):
    assert main(["demo", "ur5", "--no-viewer", "--plant", "mujoco", "--actuator", "position"]) == 0
    assert "position servos" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--plot", "x.png"], "--plot draws the measured joint rates of a plant: add --plant mujoco"),
        (["--actuator", "position"], "--actuator is an option of the MuJoCo plant: add --plant mujoco"),
        (["--missing-mass", "2"], "--missing-mass is an option of the MuJoCo plant: add --plant mujoco"),
        (["--plant", "bullet"], "invalid choice: 'bullet'"),
    ],
)
def test_plant_options_that_do_not_fit_are_one_line(arguments, message, capsys):
    assert main(["demo", "ur5", "--no-viewer", *arguments]) == 2
    assert message in capsys.readouterr().err


def test_a_robot_without_inertias_is_one_line_naming_the_repair(capsys):
    assert main(["demo", "barker_arm", "--no-viewer", "--plant", "mujoco"]) == 2
    err = capsys.readouterr().err
    assert "no <inertial> in the URDF" in err and "--missing-mass KG" in err and "Traceback" not in err
    assert main(["demo", "barker_arm", "--no-viewer", "--plant", "mujoco", "--missing-mass", "2"]) == 0


def test_one_plot_per_segment(tmp_path, capsys):
    plot = tmp_path / "rates.png"
    assert main(["demo", "ur5", "--no-viewer", "--plant", "mujoco", "--targets", "2", "--plot", str(plot)]) == 0
    assert sorted(path.name for path in tmp_path.iterdir()) == ["rates-1.png", "rates-2.png"]
    assert capsys.readouterr().out.count("plot       ") == 2
