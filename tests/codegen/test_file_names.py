"""Two robots in one ``codegen --out`` never write the same file, whatever their names; ``--check`` says which files
are missing."""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.checks.check_program_values import checked_files, compare_files, generate_checked
from quadruped_dyn.cli import main
from quadruped_dyn.codegen.file_names import (
    ROLE_SEPARATOR,
    SHARED_FILES,
    check_no_collision,
    file_layout,
    reference_header_name,
    robots_in,
)
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import is_safe_name

BASES = ("paper", "go1", "a", "robot_r", "x_d")


def _layout(name: str, out: Path = Path("out")):
    return file_layout(name, out, (reference_header_name(name),))


def suffixes() -> set[str]:
    """Every suffix the generator appends to a robot's stem (its files' roles, '-' and '.' read as the '_' a robot
    name may hold), and the shared files' names as robot names."""
    found = set()
    for path in _layout("paper").all():
        tail = path.name.removeprefix("qd_paper")
        if path.name.startswith("qd_paper"):
            found.add(re.sub(r"[-.]", "_", tail.rsplit(".", 1)[0]))
    found |= {"_" + re.sub(r"[^A-Za-z0-9]+", "_", f).strip("_") for f in SHARED_FILES}
    return {s for s in found if s}


def extended_names() -> list[str]:
    names = [base + s for base in BASES for s in suffixes()]
    names += [re.sub(r"[^A-Za-z0-9]+", "_", f.rsplit(".", 1)[0]).strip("_") for f in SHARED_FILES]  # 'check_threads'
    return [n for n in names if is_safe_name(n)]


def test_suffixes_cover_every_role():
    found = suffixes()
    assert {"_d", "_r_FL_BR", "_r_FL_FR_BL_BR", "_reference"} <= found, found


@pytest.mark.parametrize("base", BASES)
def test_no_name_built_from_a_suffix_shares_a_file(base):
    """A robot whose name is another's plus any suffix the generator uses (or a shared file's name) writes no file
    of the other's and none of the shared ones; the files' robot is read back from their names."""
    own = _layout(base).own()
    assert not own & set(SHARED_FILES)
    for name in extended_names():
        if name == base:
            continue
        other = _layout(name).own()
        assert not own & other, (base, name, sorted(own & other))
        assert not other & set(SHARED_FILES), name
        for f in other:  # the stem ends at the first role separator or extension dot
            assert re.split(rf"[{ROLE_SEPARATOR}.]", f, maxsplit=1)[0] == f"qd_{name}", f


def test_collision_check_refuses_another_robots_file(tmp_path):
    """The check is by file set: a layout that would write over a file of a robot in the folder is refused."""
    (tmp_path / "qd_go1.h").write_text("")
    assert robots_in(tmp_path) == ["go1"]
    check_no_collision(_layout("paper", tmp_path), "paper", tmp_path)
    check_no_collision(_layout("go1", tmp_path), "go1", tmp_path)  # its own files
    clash = file_layout("paper", tmp_path, ("qd_go1-d.c",))
    with pytest.raises(InputError, match="holds the generated C of 'go1', and 'paper' would write over its qd_go1-d.c"):
        check_no_collision(clash, "paper", tmp_path)


@pytest.fixture(scope="module")
def paper_folder(tmp_path_factory, paper):
    """The paper robot's generated folder (API), written once."""
    out = tmp_path_factory.mktemp("two_robots")
    files = generate_checked(paper, out)
    return out, files


def test_generation_writes_exactly_its_layout(paper_folder, paper):
    out, files = paper_folder
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in checked_files(paper, out).all())
    assert files.all() == checked_files(paper, out).all()


@pytest.mark.slow  # a second generation; the default suite has the names of every suffix and the layout written
def test_second_robot_named_with_a_suffix_keeps_the_first(paper_folder, paper, tmp_path):
    """A robot named paper + '_d' (its main source was the paper robot's derivatives) in the same --out (API):
    the paper robot's files are unchanged, so its --check stays clean; the second robot's files are its own."""
    out, files = paper_folder
    folder = tmp_path / "out"
    shutil.copytree(out, folder)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    renamed = dataclasses.replace(paper, name="paper_d")
    second = generate_checked(renamed, folder)
    after = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert {n: after[n] for n in before} == before
    assert set(after) - set(before) == second.own() == _layout("paper_d").own()
    assert not compare_files(paper, folder, files)
    assert robots_in(folder) == ["paper", "paper_d"]


def test_check_reports_missing_files(paper_folder, paper, tmp_path):
    """--check's comparison on an empty, a partial and a complete folder: absent files are 'missing', never
    'differs'."""
    out, files = paper_folder
    empty = compare_files(paper, tmp_path, files)
    assert sorted(empty.missing) == sorted(p.name for p in files.all()) and not empty.sources
    assert empty.summary().startswith("missing: ") and "differs" not in empty.summary()
    partial = tmp_path / "partial"
    shutil.copytree(out, partial)
    (partial / "qd_paper-d.c").unlink()
    (partial / "Makefile").unlink()
    (partial / "qd_paper.c").write_text("/* edited */\n")
    diff = compare_files(paper, partial, files)
    assert sorted(diff.missing) == ["Makefile", "qd_paper-d.c"] and diff.sources == ["qd_paper.c"]
    assert diff.summary() == "missing: Makefile, qd_paper-d.c; source differs from a fresh generation: qd_paper.c"
    assert not compare_files(paper, out, files)


@pytest.mark.parametrize("present", [(), ("notes.txt", "qd_go1.c")])
def test_cli_check_on_an_empty_folder_says_missing(tmp_path, present):
    """No file of the robot there: every one is missing (known from the names, before any generation)."""
    for name in present:
        (tmp_path / name).write_text("x")
    result = CliRunner().invoke(main, ["codegen", "paper", "--check", "--out", str(tmp_path)])
    assert result.exit_code == 1, result.output
    assert "missing: qd_paper.c, qd_paper.h, qd_paper-reference.h, check_qd.c" in result.output
    assert "differs" not in result.output
    assert [p for p in present if not (tmp_path / p).is_file()] == []


@pytest.mark.slow
def test_cli_second_robot_with_a_suffixed_name(paper_folder, tmp_path):
    """The CLI: a URDF named paper_r_FL_BR (the paper robot's URDF, one comment added: not the built-in's bytes) into
    the paper robot's folder writes only its own files."""
    out, _ = paper_folder
    folder = tmp_path / "out"
    shutil.copytree(out, folder)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    from quadruped_dyn.model.robot import load_robot

    urdf = tmp_path / "paper_r_FL_BR.urdf"
    urdf.write_text(load_robot("paper").urdf.read_text() + "<!-- a variant -->\n")
    result = CliRunner().invoke(main, ["codegen", str(urdf), "--out", str(folder)])
    assert result.exit_code == 0, result.output
    after = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert {n: after[n] for n in before} == before
    assert "qd_paper_r_FL_BR.c" in after and "qd_paper_r_FL_BR-r-FL_BR.c" in after
