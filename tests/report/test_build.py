"""`quadruped-dyn report`: bad input before any work, sections that tolerate missing data, and
the written page opened in a real headless Chromium with every image loaded."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.dynamics.formulas import paper_formulas
from quadruped_dyn.report import sections as rs
from quadruped_dyn.report.figures import stick_figure
from quadruped_dyn.report.gather import leg_points, robot_data
from quadruped_dyn.report.html import figure, page

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (Debian: apt-get install chromium)")

#: Appended to a copy of the page: after load, counts the images that decoded and the formulas
#: that the browser laid out as MathML (a <math> element Chromium renders has display "block math").
_PROBE = """<script>
window.addEventListener("load", () => {
  const images = [...document.images];
  const loaded = images.filter(i => i.complete && i.naturalWidth > 0).length;
  const maths = [...document.querySelectorAll("math")];
  const laidOut = maths.filter(m => getComputedStyle(m).display.includes("math") && m.getBoundingClientRect().height > 0).length;
  document.body.setAttribute("data-probe", `images ${loaded}/${images.length} math ${laidOut}/${maths.length}`);
});
</script>"""


def open_in_chromium(page_path: Path, tmp_path: Path) -> tuple[int, int, int, int]:
    """(images loaded, images, formulas laid out, formulas) of the page in headless Chromium
    with a fresh profile and networking off."""
    probe = tmp_path / "probed.html"
    probe.write_text(page_path.read_text().replace("</body>", _PROBE + "</body>"))
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=20000", "--dump-dom", probe.as_uri()]
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False).stdout
    m = re.search(r'data-probe="images (\d+)/(\d+) math (\d+)/(\d+)"', dom)
    assert m, f"the page did not finish loading in Chromium: {dom[:300]!r}"
    loaded, images, laid_out, maths = (int(x) for x in m.groups())
    return loaded, images, laid_out, maths


def test_bad_robot_is_one_line_exit_2(tmp_path):
    result = CliRunner().invoke(main, ["report", "nosuch", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and "expected a URDF path or one of" in result.stderr


def test_too_many_samples_is_one_line_exit_2_before_the_work(tmp_path, monkeypatch):
    """check refuses --samples above its cap before any work; the report ran minutes of sections
    first and then failed its term check."""
    from quadruped_dyn.report import build

    def tripwire(*args, **kwargs):
        raise AssertionError("the report started before its arguments were checked")

    monkeypatch.setattr(build, "load_with_warnings", tripwire)
    result = CliRunner().invoke(main, ["report", "paper", "--fast", "--samples", "100001", "--out", str(tmp_path)])
    assert result.exit_code == 2, result.output
    assert result.stderr.count("\n") == 1 and "expected an integer from 1 to 100,000" in result.stderr
    assert not list(tmp_path.iterdir())


def test_report_takes_the_feet(tmp_path, monkeypatch):
    """``report --foot-frames`` loads the robot on them (a wrong name: one line, exit 2, before any section) and
    hands them to the build."""
    from quadruped_dyn.report import build

    result = CliRunner().invoke(main, ["report", "paper", "--fast", "--foot-frames", "a,b,c,d", "--out", str(tmp_path)])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1, result.output
    assert "foot frame 'a' of leg FL is not a frame" in result.stderr
    given = {}
    monkeypatch.setattr(build, "build_report", lambda *a, **k: given.update(k) or (_ for _ in ()).throw(KeyboardInterrupt))
    CliRunner().invoke(main, ["report", "paper", "--fast", "--foot-frames", "FL_foot,FR_foot,BL_foot,BR_foot",
                              "--out", str(tmp_path)])
    assert given["foot_frames"] == "FL_foot,FR_foot,BL_foot,BR_foot"


def test_unwritable_out_is_one_line_exit_2(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = CliRunner().invoke(main, ["report", "paper", "--out", str(blocker)])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and "expected a writable --out directory" in result.stderr


def test_sections_tolerate_missing_data():
    """Producers change in parallel: a renderer given less (or more) than today's keys says so."""
    for section in (rs.terms_section(None), rs.generated_c_section(None, None), rs.reduced_section(None),
                    rs.notebooks_section(None), rs.experiment_section({"trot": None}, [], {})):
        assert section.verdict == "not available"
        assert "not available" in section.body
    minimal = {"runs": {"paper": {"stopped_at_s": None}}, "physics_check": {"max_deviation": 0.3, "plot": [1]},
               "max_pct_err": {"j10": {"q": 0.25}}, "max_pct_err_overall": {"q": 0.5}}
    section = rs.experiment_section({"trot": minimal}, [f"j{k}" for k in range(12)], {})
    assert section.verdict == "result" and "max_deviation" in section.body
    assert "BR HFE q 2.5e-01 %" in section.headline and "5.0e-01" in section.headline


def test_failing_term_is_red_and_fails():
    check = {"samples": 1, "seed": 0, "passed": False, "build_seconds": 0.1,
             "terms": [{"name": "M_full", "max_abs_err": float("nan"), "max_rel_err": float("nan"), "tol": 1e-10,
                        "passed": False}], "grf": []}
    section = rs.terms_section(check)
    assert section.verdict == "FAIL" and 'class="bad"' in section.body


@needs_chromium
def test_page_renders_in_chromium(paper, tmp_path):
    """Figures and formulas of the page machinery, in a real browser (the full report: the slow test)."""
    fig = figure(stick_figure(leg_points(paper, paper.standing_q), "paper"), "stick figure")
    formulas = [{"title": f.title, "latex": f.latex, "mathml": f.mathml, "max_err_vs_pinocchio": 0.0, "tol": 1e-10}
                for f in paper_formulas(paper)]
    sizes = [{"name": "G_full", "instructions": 1, "inputs": "q[19]", "outputs": "G[18]", "nonzeros": 1}]
    sections = [rs.robot_section(robot_data(paper, []), fig), rs.symbolic_section(formulas, "", sizes, fig)]
    path = tmp_path / "page.html"
    path.write_text(page("test", "", sections))
    assert "http" not in path.read_text()  # nothing to fetch
    loaded, images, laid_out, maths = open_in_chromium(path, tmp_path)
    assert (loaded, laid_out) == (images, maths) == (2, 3)


@pytest.mark.slow
@needs_chromium
def test_full_report_renders(tmp_path):
    """`report paper --fast` end to end (~4 min on a shared 2-core machine): every section present, no failure, every
    image loaded and every formula laid out in Chromium."""
    result = CliRunner().invoke(main, ["report", "paper", "--out", str(tmp_path), "--fast"])
    assert result.exit_code == 0, result.output
    path = tmp_path / "paper" / "report.html"
    html = path.read_text()
    for key in ("robot", "terms", "grf", "reduced", "experiment", "c", "symbolic", "notebooks", "versions"):
        assert f'<section id="{key}">' in html
    assert "v-fail" not in html.split("<h2>Summary</h2>")[1].split("</table>")[0]
    assert not re.search(r'(src|href)="https?:', html)
    header = (Path(__file__).resolve().parents[2] / "casadi_gen" / "qd_paper.h").read_text()
    for name in re.findall(r"^ \*   (qd_\w+)\(.*iw \d+, w \d+", header, flags=re.M):  # every generated function, checked
        assert re.search(rf"<td>{name}</td>.*?v-pass", html), name
    if importlib.util.find_spec("mujoco") and importlib.util.find_spec("idyntree"):  # the xlib extra: the comparison ran
        assert "<th>vs quadruped_dyn</th>" in html
    loaded, images, laid_out, maths = open_in_chromium(path, tmp_path)
    assert images >= 8 and loaded == images
    assert maths >= 3 and laid_out == maths


def test_steps_are_numbered_up_to_their_total(tmp_path, monkeypatch, capsys):
    """Every progress line of the report is "[k/N]" with k running 1..N (no "[11/10]"), whatever
    the sections do: here every gatherer fails at once, so only the numbering is exercised."""
    from quadruped_dyn.report import build

    def broken(*_args, **_kwargs):
        raise RuntimeError("stubbed out")

    for name in ("_terms_section", "_grf_section", "_reduced_section", "_experiment_section", "_c_section",
                 "_symbolic_section", "optimal_trot", "closed_loop", "_notebooks_section"):
        monkeypatch.setattr(build, name, broken)
    result = build.build_report("paper", tmp_path, with_notebooks=True, compile_ahead=False)
    err = capsys.readouterr().err
    starts = re.findall(r"^\[(\d+)/(\d+)\] .* \.\.\.$", err, flags=re.M)
    total = int(starts[0][1])
    assert [(int(k), int(n)) for k, n in starts] == [(k, total) for k in range(1, total + 1)]
    assert total == len(result.sections) and result.path.is_file()  # one step per section
    # the notebooks, then the generated-C step (it waits for the warm process) run last; the page keeps its order
    labels = re.findall(r"^\[\d+/\d+\] (.*) \.\.\.$", err, flags=re.M)
    assert labels[-3:] == ["notebooks", "generated C and the benchmark", "versions, writing the page"]
    assert [s.key for s in result.sections] == ["robot", "terms", "grf", "reduced", "experiment", "c", "symbolic",
                                                "optimal_control", "closed_loop", "notebooks", "versions"]


def test_notebooks_are_shared_with_the_warm_process_from_both_ends(monkeypatch):
    """The notebooks step takes the notebooks the warm process has not started from the back, one at
    a time (so both processes execute notebooks), stops at the first one the warm process started,
    waits for the warm process's results, and shows them all in their own order."""
    from concurrent.futures import Future

    from quadruped_dyn.progress import Steps
    from quadruped_dyn.report import build

    paths = [Path(f"n{k}.ipynb") for k in range(5)]
    monkeypatch.setattr(build, "notebook_list", lambda robot: (paths, ""))
    futures: list[Future] = [Future() for _ in paths]
    futures[0].set_running_or_notify_cancel()  # the warm process is executing n0: it cannot be cancelled
    order: list[str] = []

    def here(path):
        order.append(path.name)
        if path.name == "n3.ipynb":  # meanwhile the warm process finished n0 and started n1
            futures[0].set_result({"name": "n0.ipynb", "seconds": 0.0, "errors": 0, "html": "<p>n0.ipynb warm</p>"})
            futures[1].set_running_or_notify_cancel()
            futures[1].set_result({"name": "n1.ipynb", "seconds": 0.0, "errors": 0, "html": "<p>n1.ipynb warm</p>"})
        return {"name": path.name, "seconds": 0.0, "errors": 0, "html": f"<p>{path.name} here</p>"}

    monkeypatch.setattr(build, "executed_notebook", here)
    job = build._Job(None, [], Path("."), False, 1, False, Steps(1, enabled=False), notebooks_ahead=futures)
    section = build._notebooks_section(job)
    assert order == ["n4.ipynb", "n3.ipynb", "n2.ipynb"] and all(f.cancelled() for f in futures[2:])
    body = section.body
    assert (body.index("n0.ipynb warm") < body.index("n1.ipynb warm") < body.index("n2.ipynb here")
            < body.index("n3.ipynb here") < body.index("n4.ipynb here"))


def _report_with_experiment_files(monkeypatch, tmp_path, run: int, figure_raises: BaseException | None = None):
    """``build_report`` with every section but the robot's stubbed out, and an experiment section that
    writes its JSON (``write_json``) and then its plot (``save_figure``, raising ``figure_raises``
    if given) into the report's folder, as ``gather.experiment`` does."""
    import matplotlib.pyplot as plt

    from quadruped_dyn.experiment.validation_files import output_paths
    from quadruped_dyn.files import safe_write
    from quadruped_dyn.files.json import write_json
    from quadruped_dyn.report import build
    from quadruped_dyn.report.html import Section

    def broken(*_args, **_kwargs):
        raise RuntimeError("stubbed out")

    for name in ("_terms_section", "_grf_section", "_reduced_section", "_c_section", "_symbolic_section",
                 "optimal_trot", "closed_loop"):
        monkeypatch.setattr(build, name, broken)
    if figure_raises is not None:
        def raising(*_args, **_kwargs):
            raise figure_raises

        monkeypatch.setattr(safe_write, "save_figure", raising)

    def experiment_section(job):
        paths = output_paths(job.target, job.robot.name, "trot")
        write_json(paths["json"], {"run": run})
        fig = plt.figure()
        fig.suptitle(f"run {run}")
        safe_write.save_figure(fig, paths["plot"])
        plt.close(fig)
        return Section("experiment", "The paper's experiment", "pass", f"run {run}", "")

    monkeypatch.setattr(build, "_experiment_section", experiment_section)
    return build.build_report("paper", tmp_path, fast=True, with_notebooks=False, show_progress=False,
                              compile_ahead=False)


def _tree(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root`` (hidden ones too): a file's bytes, None for a directory."""
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else None) for p in sorted(root.rglob("*"))}


def test_an_interrupted_report_leaves_the_previous_one_as_it_was(tmp_path, monkeypatch):
    """The page, the JSON and the plots of a report are one output set: an interrupt (here in a figure
    writer, after the new JSON was written) leaves the previous report's files as they were, byte for
    byte, and no temporary file or folder behind."""
    _report_with_experiment_files(monkeypatch, tmp_path, 1)
    before = _tree(tmp_path)
    assert {"paper/report.html", "paper/paper_trot_validation.json", "paper/paper_trot_BR_HFE.png"} <= set(before)
    with pytest.raises(KeyboardInterrupt):
        _report_with_experiment_files(monkeypatch, tmp_path, 2, figure_raises=KeyboardInterrupt())
    assert _tree(tmp_path) == before


def test_a_failed_section_leaves_no_old_file_beside_its_new_ones(tmp_path, monkeypatch):
    """A section that fails half-way (its figure writer raises after its JSON was written) is FAIL on the
    page, and the report replaces the previous one's files as a whole: the new JSON is not published
    beside the previous report's plot."""
    _report_with_experiment_files(monkeypatch, tmp_path, 1)
    result = _report_with_experiment_files(monkeypatch, tmp_path, 2, figure_raises=RuntimeError("no figure"))
    assert next(s for s in result.sections if s.key == "experiment").verdict == "FAIL"
    folder = tmp_path / "paper"
    assert json.loads((folder / "paper_trot_validation.json").read_text()) == {"run": 2}
    assert not (folder / "paper_trot_BR_HFE.png").exists()
    assert sorted(p.name for p in folder.iterdir()) == ["paper_trot_validation.json", "report.html"]


def test_a_directory_in_place_of_report_html_is_refused_before_the_work(tmp_path):
    """It was found when the page was published, after every step (minutes): now exit 2 at once."""
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.report.build import prepare

    (tmp_path / "paper" / "report.html").mkdir(parents=True)
    with pytest.raises(InputError, match=r"report.html' ?: it exists and is not a regular file"):
        prepare("paper", tmp_path)
    assert [p.name for p in (tmp_path / "paper").iterdir()] == ["report.html"]  # no staging folder made


@pytest.mark.parametrize("kind", ["link", "file"])
def test_a_link_or_file_in_place_of_the_c_folder_is_refused_before_the_work(tmp_path, kind):
    """Found when the report published its generated C (minutes in): now exit 2 at once, nothing made."""
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.report.build import prepare

    folder = tmp_path / "paper"
    folder.mkdir()
    outside = tmp_path / "outside"
    outside.mkdir()
    if kind == "link":
        (folder / "c").symlink_to(outside)
    else:
        (folder / "c").write_text("not a folder")
    said = "symbolic link; expected a directory" if kind == "link" else "is a file; expected a directory"
    with pytest.raises(InputError, match=said):
        prepare("paper", tmp_path)
    assert [p.name for p in folder.iterdir()] == ["c"] and not any(outside.iterdir())


def test_a_killed_reports_staging_folder_is_removed_by_the_next_a_running_ones_kept(tmp_path):
    """SIGKILL leaves the hidden staging folder (no cleanup runs); the next report in the folder removes it when
    the process named in it is gone, and keeps one whose process runs (a second report at the same time) and one
    of another host (its pids are not this machine's)."""
    import subprocess
    import sys

    from quadruped_dyn.report.build import _host, _staging

    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                          check=True)
    dead = tmp_path / f".report.{int(gone.stdout)}@{_host()}.abc.partial"
    running = tmp_path / f".report.{os.getppid()}@{_host()}.def.partial"
    elsewhere = tmp_path / f".report.{int(gone.stdout)}@{_host()}-other.ghi.partial"
    for folder in (dead, running, elsewhere):
        (folder / "c").mkdir(parents=True)
        (folder / "report.html").write_text("half")
    with _staging(tmp_path) as staging:
        assert staging.name.startswith(f".report.{os.getpid()}@{_host()}.")
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted([running.name, elsewhere.name, staging.name])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([running.name, elsewhere.name])


@pytest.mark.parametrize("pid", ["99999999999999999999", "²", "١٢"])
def test_a_staging_folder_whose_pid_no_process_can_have_is_kept_without_an_error(tmp_path, pid):
    """A hidden folder of the staging pattern whose pid is beyond any process id (os.kill raised OverflowError) or
    not ASCII digits ('²'.isdigit(): int() raised ValueError; '١٢' read as pid 12) is not one a report made: the
    next report starts and leaves it as it is."""
    from quadruped_dyn.report.build import _host, _staging

    odd = tmp_path / f".report.{pid}@{_host()}.abc.partial"
    (odd / "c").mkdir(parents=True)
    with _staging(tmp_path) as staging:
        assert staging.is_dir()
    assert [p.name for p in tmp_path.iterdir()] == [odd.name] and (odd / "c").is_dir()
