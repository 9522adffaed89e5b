"""Every structural fault of a URDF is a LoadError naming the joint or link, before Pinocchio
sees the file; encodings are honoured; size limits hold (kinematics.urdf, urdf_structure)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pinocchio as pin
import pytest

import pinrate
from pinrate.kinematics.urdf_structure import MAX_DEPTH, MAX_JOINTS

LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def joint(name: str, parent: str, child: str, kind: str = "revolute", inner: str = LIMIT, axis: str = "0 0 1") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 0.3"/><axis xyz="{axis}"/>{inner}</joint>'
    )


def robot(*parts: str, links: str = "abc") -> str:
    return '<robot name="r">' + "".join(f'<link name="{link}"/>' for link in links) + "".join(parts) + "</robot>"


GOOD = (joint("j1", "a", "b"), joint("j2", "b", "c"))

# (case, URDF text, words the message must contain)
BROKEN = [
    ("revolute without limit", robot(joint("j1", "a", "b", inner=""), GOOD[1]), ["'j1'", "revolute", "<limit>"]),
    ("prismatic without limit", robot(joint("j1", "a", "b", "prismatic", ""), GOOD[1]), ["'j1'", "prismatic"]),
    ("limit without effort", robot(joint("j1", "a", "b", inner='<limit velocity="1"/>'), GOOD[1]), ["'j1'", "effort"]),
    ("missing parent link", robot(joint("j1", "zz", "b"), GOOD[1]), ["'j1'", "parent link 'zz'"]),
    ("missing child link", robot(GOOD[0], joint("j2", "b", "zz")), ["'j2'", "child link 'zz'"]),
    (
        "no parent element",
        robot(GOOD[0], '<joint name="j2" type="fixed"><child link="c"/></joint>'),
        ["'j2'", "<parent"],
    ),
    ("duplicate link", robot(*GOOD, links="abcb"), ["two links", "'b'"]),
    ("duplicate joint", robot(GOOD[0], joint("j1", "b", "c")), ["two joints", "'j1'"]),
    ("link with two parents", robot(*GOOD, joint("j3", "d", "c"), links="abcd"), ["'j3'", "link 'c'", "'j2'"]),
    ("two roots", robot(GOOD[0], links="abd"), ["2 root links", "'a'", "'d'"]),
    ("cycle", robot(*GOOD, joint("j3", "c", "a")), ["cycle"]),
    ("unknown type", robot(joint("j1", "a", "b", "hinge"), GOOD[1]), ["'j1'", "'hinge'", "revolute"]),
    ("no type", robot(joint("j1", "a", "b").replace(' type="revolute"', ""), GOOD[1]), ["'j1'", "no type"]),
    (
        "NaN in origin",
        robot(joint("j1", "a", "b").replace('xyz="0 0 0.3"', 'xyz="0 nan 0.3"'), GOOD[1]),
        ["'j1'", "origin"],
    ),
    ("text in rpy", robot(joint("j1", "a", "b", inner=LIMIT + '<origin rpy="0 abc 0"/>'), GOOD[1]), ["'j1'", "rpy"]),
    (
        "two numbers in xyz",
        robot(joint("j1", "a", "b").replace('xyz="0 0 0.3"', 'xyz="0 1"'), GOOD[1]),
        ["'j1'", "3 finite"],
    ),
    ("inf in axis", robot(joint("j1", "a", "b", axis="0 inf 1"), GOOD[1]), ["'j1'", "axis"]),
    (
        "overflowing origin",
        robot(joint("j1", "a", "b").replace('xyz="0 0 0.3"', 'xyz="1e308 0 0"'), GOOD[1]),
        ["'j1'", "within"],
    ),
    ("overflowing axis", robot(joint("j1", "a", "b", axis="1e308 1e308 0"), GOOD[1]), ["'j1'", "axis", "within"]),
    ("zero axis", robot(joint("j1", "a", "b", axis="0 0 0"), GOOD[1]), ["'j1'", "axis is zero"]),
    ("text in limit", robot(joint("j1", "a", "b", inner=LIMIT.replace('"-1"', '"low"')), GOOD[1]), ["'j1'", "lower"]),
    ("lower above upper", robot(joint("j1", "a", "b", inner=LIMIT.replace('"-1"', '"2"')), GOOD[1]), ["'j1'", "above"]),
    (
        "negative velocity limit",
        robot(joint("j1", "a", "b", inner=LIMIT.replace('velocity="1"', 'velocity="-1"')), GOOD[1]),
        ["'j1'", "negative"],
    ),
    (
        "NaN in a link's inertial origin",
        robot(*GOOD).replace('<link name="b"/>', '<link name="b"><inertial><origin xyz="nan 0 0"/></inertial></link>'),
        ["link 'b'"],
    ),
    (
        "no moving joint",
        robot(joint("j1", "a", "b", "fixed", ""), joint("j2", "b", "c", "fixed", "")),
        ["no moving joint"],
    ),
    ("no link", '<robot name="r"></robot>', ["no <link>"]),
    ("unnamed joint", robot(GOOD[0].replace(' name="j1"', ""), GOOD[1]), ["<joint> has no name"]),
]


@pytest.mark.parametrize(("case", "text", "words"), BROKEN, ids=[case for case, _, _ in BROKEN])
def test_a_broken_urdf_is_a_load_error_naming_the_culprit(
    tmp_path: Path, case: str, text: str, words: list[str]
) -> None:
    path = tmp_path / "broken.urdf"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(pinrate.LoadError) as caught:
        pinrate.load(path)
    message = str(caught.value)
    assert "broken.urdf" in message or "robot 'r'" in message
    for word in words:
        assert word in message, (case, message)


def test_the_good_urdf_of_the_table_loads(tmp_path: Path) -> None:
    path = tmp_path / "good.urdf"
    path.write_text(robot(*GOOD), encoding="utf-8")
    assert pinrate.load(path).joint_names == ("j1", "j2")


def test_urdfdom_reasons_replace_its_generic_message(tmp_path: Path) -> None:
    # A fault only urdfdom notices: its own reason, not "does not contain a valid URDF model".
    path = tmp_path / "damping.urdf"
    path.write_text(robot(joint("j1", "a", "b", inner=LIMIT + '<dynamics damping="x"/>'), GOOD[1]), "utf-8")
    with pytest.raises(pinrate.LoadError, match=r"damping value \(x\) is not a valid float.*joint \[j1\]"):
        pinrate.load(path)


def test_what_urdfdom_skips_is_a_warning_not_lost(tmp_path: Path) -> None:
    path = tmp_path / "mass.urdf"
    path.write_text(
        robot(*GOOD).replace('<link name="c"/>', '<link name="c"><inertial><mass value="abc"/></inertial></link>'),
        "utf-8",
    )
    with pytest.warns(UserWarning, match=r"skipped parts.*mass \[abc\] is not a float"):
        assert pinrate.load(path).nv == 2


@pytest.mark.parametrize("encoding", ["UTF-16", "ISO-8859-1", "UTF-8"])
def test_the_encoding_declaration_is_honoured(tmp_path: Path, encoding: str) -> None:
    # A non-ASCII name survives only if the bytes are decoded as the declaration says.
    text = f'<?xml version="1.0" encoding="{encoding}"?>' + robot(
        joint("épaule", "a", "b"), joint("coude", "b", "c")
    ).replace('"a"', '"bâti"')
    path = tmp_path / "encoded.urdf"
    path.write_bytes(text.encode(encoding))
    loaded = pinrate.load(path)
    assert loaded.joint_names == ("épaule", "coude")
    assert "bâti" in [frame.name for frame in loaded.model.frames]


def test_a_utf8_byte_order_mark_is_read(tmp_path: Path) -> None:
    path = tmp_path / "bom.urdf"
    path.write_bytes(b"\xef\xbb\xbf" + robot(*GOOD).encode())
    assert pinrate.load(path).nv == 2


def test_undeclared_non_utf8_bytes_are_refused_with_the_offset(tmp_path: Path) -> None:
    path = tmp_path / "latin.urdf"
    path.write_bytes(robot(*GOOD).replace('"a"', '"bâti"').encode("latin-1"))
    with pytest.raises(pinrate.LoadError, match=r"not valid utf-8 text at byte \d+ \(declare its encoding"):
        pinrate.load(path)


def test_a_lone_surrogate_is_refused_not_a_traceback(tmp_path: Path) -> None:
    # UTF-7 decodes "+2D8-" to a lone surrogate, which ElementTree's encoder raised on.
    path = tmp_path / "utf7.urdf"
    path.write_bytes(b'<?xml version="1.0" encoding="utf-7"?>' + robot(*GOOD).replace('"a"', '"a+2D8-"').encode())
    with pytest.raises(pinrate.LoadError, match="not valid utf-7 text: a lone surrogate at character"):
        pinrate.load(path)


def test_an_unknown_encoding_is_named(tmp_path: Path) -> None:
    path = tmp_path / "klingon.urdf"
    path.write_text('<?xml version="1.0" encoding="klingon-8"?>' + robot(*GOOD), encoding="utf-8")
    with pytest.raises(pinrate.LoadError, match="unknown XML encoding 'klingon-8'"):
        pinrate.load(path)


def chain(count: int, kind: str = "revolute") -> str:
    inner = LIMIT if kind != "fixed" else ""
    links = "".join(f'<link name="l{i}"/>' for i in range(count + 1))
    joints = "".join(joint(f"j{i}", f"l{i}", f"l{i + 1}", kind, inner) for i in range(count))
    return f'<robot name="chain">{links}{joints}</robot>'


def test_too_many_joints_are_refused_before_pinocchio_and_the_limit_is_overridable(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "long.urdf"
    path.write_text(chain(MAX_JOINTS + 1), encoding="utf-8")
    with pytest.raises(
        pinrate.LoadError, match=f"{MAX_JOINTS + 1} moving joints, more than pinrate's limit of {MAX_JOINTS}"
    ):
        pinrate.load(path)
    assert pinrate.load(path, max_joints=MAX_JOINTS + 1).nv == MAX_JOINTS + 1
    monkeypatch.setenv("PINRATE_MAX_JOINTS", str(MAX_JOINTS + 1))
    assert pinrate.load(path).nv == MAX_JOINTS + 1
    monkeypatch.setenv("PINRATE_MAX_JOINTS", "lots")
    with pytest.raises(pinrate.LoadError, match="PINRATE_MAX_JOINTS"):
        pinrate.load(path)
    with pytest.raises(pinrate.InputError, match="max_joints"):
        pinrate.load(path, max_joints=0)


def test_a_chain_deep_enough_to_crash_the_parser_is_refused(tmp_path: Path) -> None:
    # urdfdom segfaults past about 3000 links in one chain: run in a child process, so a crash
    # fails this test instead of killing the test session.
    path = tmp_path / "deep.urdf"
    text = chain(5000, "fixed").replace('<child link="l1"/>', '<child link="l1"/>', 1)
    path.write_text(text.replace('name="j0" type="fixed"', 'name="j0" type="continuous"'), encoding="utf-8")
    code = f"import pinrate\ntry:\n pinrate.load({str(path)!r})\nexcept pinrate.LoadError as e:\n print(e)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr[-500:]
    assert f"limit of {MAX_DEPTH} links in one chain" in result.stdout


def test_xacro_text_in_a_urdf_file_is_refused_with_what_to_do(tmp_path: Path) -> None:
    """A ``.xacro`` file is expanded (tests/robots/test_xacro.py); xacro elements in a ``.urdf`` are refused."""
    macro = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:property name="l" value="1"/></robot>'
    path = tmp_path / "arm.urdf"
    path.write_text(macro, encoding="utf-8")
    with pytest.raises(pinrate.LoadError, match=r"xacro file.*name it robot\.urdf\.xacro.*expand it first"):
        pinrate.load(path)
    undeclared = tmp_path / "undeclared.urdf"
    undeclared.write_text('<robot name="r"><xacro:include filename="x"/></robot>', encoding="utf-8")
    with pytest.raises(pinrate.LoadError, match="expand it first"):
        pinrate.load(undeclared)


def test_an_expanded_file_that_keeps_the_xacro_namespace_loads(tmp_path: Path) -> None:
    path = tmp_path / "expanded.urdf"
    path.write_text(robot(*GOOD).replace("<robot ", '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" '), "utf-8")
    assert pinrate.load(path).nv == 2


def test_a_model_too_big_for_memory_is_a_load_error(monkeypatch: pytest.MonkeyPatch) -> None:
    # What Pinocchio does when a model's data does not fit (1000 joints: 8 GB): MemoryError.
    def out_of_memory(model: pin.Model) -> None:
        raise MemoryError

    model = pinrate.load("ur5").model
    monkeypatch.setattr(pin.Model, "createData", out_of_memory)
    with pytest.raises(pinrate.LoadError, match="data for 6 joints does not fit in memory"):
        pinrate.Robot(model, name="ur5")
