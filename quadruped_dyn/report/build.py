"""``quadruped-dyn report``: one self-contained HTML page of everything the toolkit knows about
a robot (``<out>/<robot>/report.html``), with its files beside it (the experiment's plots and
JSON, the generated C). The steps write their files into a hidden folder inside it; the page and
they are then put in place as one output set (``files.safe_write.publish``), replacing the previous
report's (``report.html``, ``c/``, ``<robot>_*``): an interrupted or failed report leaves the
previous one as it was, never new JSON beside old plots.

Each section is gathered by a function here, from the toolkit's public APIs, and rendered by
``report_sections`` from plain data (the same dicts the commands print as JSON). A section
whose gathering raises shows FAIL with the message; the page is written anyway.

Conventions of the numbers shown: trunk frame b (x forward, y left, z up), world z up;
joint order FL, FR, BL, BR x (HAA, HFE, KFE); quaternions (x, y, z, w); a = vdot, i.e. the
trunk's spatial acceleration, as everywhere in the project.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import tempfile
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime, timezone
from functools import partial
from pathlib import Path
from typing import Any

from quadruped_dyn.checks.sample_counts import CHECK_SAMPLES, check_samples
from quadruped_dyn.files.cache import writable_cache
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.files.provenance import check_source, record_source
from quadruped_dyn.files.safe_write import dir_place, output_dir, output_path, output_set, publish, replaceable, write_text
from quadruped_dyn.model.registry import robot_path
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.robot_identity import urdf_source
from quadruped_dyn.progress import Steps
from quadruped_dyn.report import warm
from quadruped_dyn.report.gather import (
    C_FOLDER,
    FRICTION_MU,
    closed_loop,
    cross_library,
    embedded_footprint,
    executed_notebook,
    experiment,
    generated_c,
    grf_posture,
    leg_points,
    load_with_warnings,
    notebook_list,
    optimal_trot,
    reduced_rows,
    robot_data,
    symbolic_data,
    versions,
)
from quadruped_dyn.report.html import Section, esc, figure, page

Progress = Steps  # numbered steps with a bar inside a long one (quadruped_dyn.progress)


#: Gait cycles of the report's closed loop (walk and trot, every controller): 2 keeps the main job
#: short (9 controllers x 2 gaits x 2 cycles, ~32 s simulated); `quadruped-dyn control --cycles 10`
#: and the slow tests run the 10-cycle study (docs/closed_loop.md).
REPORT_CLOSED_LOOP_CYCLES = 2


#: Steps run after the others, in this order (the page keeps its own): the generated-C step waits
#: for the Cortex-M builds and the benchmark harness of the warm process (warm.py), so it comes
#: last; before it the notebooks, which this process executes itself unless the warm process got to
#: them first (a warm cache); the steps that need neither run meanwhile.
RUN_LATE = ("notebooks", "c")


def prepare(robot_arg: str, out: str | Path, samples: int = CHECK_SAMPLES) -> tuple[Path, Path]:
    """Validate the arguments before any work: (URDF path, the robot's output directory).
    InputError for an unknown robot, a number of term-check samples ``run_check`` refuses (it runs
    minutes into the report), an output directory that cannot be written or that holds another URDF's
    outputs of the same robot name (``files.provenance``)."""
    check_samples(samples)
    urdf = robot_path(robot_arg)
    out_dir = writable_dir(out, f"--out '{out}'", "a writable --out directory")
    source = urdf_source(urdf)
    check_source(out_dir, source)  # another URDF's report of the same name is never overwritten
    # as load_robot names it: a safe name, one path component; never a link out of --out
    target = output_dir(out_dir, source.name)
    # what is in the way of the publish (minutes later) is refused now
    replaceable([target / "report.html"])  # a directory in its place
    dir_place(target, C_FOLDER)  # a link or a file in place of the generated C's folder
    writable_cache()  # its steps build C there
    return urdf, writable_dir(target, f"--out '{target}'", "a writable --out directory")


# ----------------------------------------------------------------------------- gathering


# ----------------------------------------------------------------------------- the report


@dataclass(frozen=True)
class ReportResult:
    path: Path
    sections: list[Section]

    @property
    def passed(self) -> bool:
        return all(s.verdict != "FAIL" for s in self.sections)

    def summary(self) -> str:
        width = max(len(s.title) for s in self.sections)
        lines = [f"{'section':<{width}}  {'result':<13}  headline"]
        lines += [f"{s.title:<{width}}  {s.verdict:<13}  {s.headline}" for s in self.sections]
        lines.append(f"wrote {printable(self.path)}")  # one line, whatever --out holds
        return "\n".join(lines)


def _failed(key: str, title: str, e: Exception) -> Section:
    message = f"{type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else ''}"
    return Section(key, title, "FAIL", message[:160], f'<p class="warn">Could not build this section: {esc(message)}</p>')


@dataclass
class _Job:
    """What the sections of one report share: the robot, where its files go, the options, and the
    term check's dict (the GRF section shows its rows too)."""

    robot: Robot
    urdf_warnings: list[str]
    target: Path  # where the steps write their files (published with the page)
    fast: bool
    samples: int
    footprint: bool
    progress: Progress
    check: dict[str, Any] | None = None
    notebooks_ahead: list[Future[dict[str, Any]]] | None = None  # executed by the warm process (warm.py)
    folder: Path | None = None  # the report's folder, where the page says its files are (else ``target``)


def _attempt(key: str, title: str, build: Callable[[], Section]) -> Section:
    """The section ``build`` returns, or a FAIL section with its message: one section failing must not
    lose the others (it is reported on the page)."""
    try:
        return build()
    except Exception as e:
        return _failed(key, title, e)


def build_report(robot_arg: str = "paper", out: str | Path = "results", fast: bool = False,
                 samples: int = CHECK_SAMPLES, with_notebooks: bool = True, show_progress: bool = True,
                 compile_ahead: bool = True, footprint: bool = False, foot_frames: object = None) -> ReportResult:
    """Write ``<out>/<robot>/report.html`` (see the module docstring); ``fast`` skips the
    benchmark; ``footprint`` adds the Cortex-M cross builds (code size and stack; minutes on a
    cold cache); ``compile_ahead`` compiles the later steps' C in a second process from the start
    (``warm.py``); ``foot_frames`` as ``load_robot``'s. Arguments are validated (InputError) before any work."""
    import matplotlib

    matplotlib.use("Agg")  # figures go into the page, never to a window
    _, target = prepare(robot_arg, out, samples)
    robot, urdf_warnings = load_with_warnings(robot_arg, foot_frames)  # a URDF's or a foot's error before any line
    steps = _steps(samples, fast, with_notebooks)
    progress = Progress(len(steps) + 2, show_progress)  # loading, the steps, writing the page
    done = progress.step(f"loading {robot_arg}")
    with _staging(target) as staging:
        job = _Job(robot, urdf_warnings, staging, fast, samples, footprint, progress, folder=target)
        pool = None
        stopped = False
        try:
            if compile_ahead:  # in the try: a signal right after the start still stops the pool below
                ahead = notebook_list(robot)[0] if with_notebooks else []
                pool, _, job.notebooks_ahead = warm.start(robot.urdf, with_benchmark=not fast,
                                                          with_footprint=footprint and not fast, notebooks=ahead,
                                                          foot_frames=tuple(leg.foot_frame for leg in robot.legs))
            sections = [_attempt("robot", "The robot", lambda: _robot_section(job))]
            done()
            built: dict[str, Section] = {}
            late_last = sorted(steps, key=lambda step: RUN_LATE.index(step[1]) + 1 if step[1] in RUN_LATE else 0)
            for label, key, title, build in late_last:
                done = progress.step(label)
                built[key] = _attempt(key, title, partial(build, job))
                done()
            sections += [built[key] for _, key, _, _ in steps]  # page order
        except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the warm process's work is not waited for
            stopped = True
            raise
        finally:
            if pool is not None:
                warm.stop(pool, now=stopped)  # no process outlives the command
        done = progress.step("versions, writing the page")
        from quadruped_dyn.report import sections as rs

        sections.append(rs.versions_section(versions()))
        subtitle = (f"{robot.urdf} — built {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC by quadruped-dyn report"
                    + (" --fast" if fast else "") + (" --footprint" if footprint and not fast else ""))
        write_text(output_path(staging, "report.html"), page(f"quadruped_dyn report: {robot.name}", subtitle, sections))
        with output_set():  # the page and every file of the steps, or none of them
            publish(staging, target, replaces=[target / "report.html", *target.glob(f"{robot.name}_*"),
                                               *target.glob(f"{C_FOLDER}/*")])
            record_source(target.parent, robot)
    done()
    return ReportResult(target / "report.html", sections)


STAGING_PREFIX, STAGING_SUFFIX = ".report.", ".partial"  # .report.<pid>@<host>.<random>.partial


@contextmanager
def _staging(target: Path) -> Iterator[Path]:
    """A new hidden folder in ``target`` for the report's files until they are published; removed at the end.
    Those a killed report of this machine left (SIGKILL, a power cut: its process is gone) are removed first; a
    running report's, and another machine's or container's (its host name differs: its pids are not ours), are left."""
    here = _host()
    for old in target.glob(f"{STAGING_PREFIX}*{STAGING_SUFFIX}"):
        pid, _, host = old.name.removeprefix(STAGING_PREFIX).split(".")[0].partition("@")
        if (host == here and re.fullmatch(r"[0-9]{1,9}", pid) and not _alive(int(pid)) and old.is_dir()
                and not old.is_symlink()):  # ASCII digits a pid can have: another name is not a report's
            shutil.rmtree(old, ignore_errors=True)
    staging = Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}@{here}.", suffix=STAGING_SUFFIX, dir=target))
    try:
        yield staging
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _host() -> str:
    """This machine's name as a file name may hold it (letters, digits, '-')."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:64] or "host"


def _alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (one of another user counts: never remove what may be in use)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def _steps(samples: int, fast: bool, with_notebooks: bool) -> list[tuple[str, str, str, Callable[[_Job], Section]]]:
    """(progress line, key, title, builder of the job) of every section after the robot's, in page order."""
    from quadruped_dyn.report import sections as rs

    notebooks_built: Callable[[_Job], Section] = (
        _notebooks_section if with_notebooks else (lambda job: rs.notebooks_section(None, "not executed for this page")))
    return [
        (f"every term against Pinocchio ({samples} random states) and other libraries", "terms",
         "Every term against Pinocchio", _terms_section),
        ("GRF systems", "grf", "Ground-reaction-force systems", _grf_section),
        ("reduced model of every stance set", "reduced", "Reduced model per stance set", _reduced_section),
        ("the paper's experiment: trot and static walk", "experiment", "The paper's experiment: trot and static walk",
         _experiment_section),
        ("generated C" + ("" if fast else " and the benchmark"), "c", "Generated C", _c_section),
        ("symbolic terms", "symbolic", "Symbolic terms", _symbolic_section),
        ("a trot the robot can do", "optimal_control", "A trot the robot can do",
         lambda job: rs.optimal_control_section(*optimal_trot(job.robot, job.target))),
        ("closed loop in MuJoCo", "closed_loop", "Closed loop in MuJoCo",
         lambda job: rs.closed_loop_section(closed_loop(job.robot, job.target, REPORT_CLOSED_LOOP_CYCLES))),
        ("notebooks", "notebooks", "Notebooks, executed", notebooks_built),
    ]


def _robot_section(job: _Job) -> Section:
    from quadruped_dyn.report import sections as rs
    from quadruped_dyn.report.figures import stick_figure

    robot = job.robot
    chains = leg_points(robot, robot.standing_q)
    fig = figure(stick_figure(chains, f"{robot.name} at its standing posture"), "stick figure of the robot",
                 "legs and feet at robot.standing_q, trunk level, lowest foot on the ground")
    return rs.robot_section(robot_data(robot, job.urdf_warnings), fig)


def _terms_section(job: _Job) -> Section:
    from quadruped_dyn.checks.terms import N_MODELS, run_check
    from quadruped_dyn.report import sections as rs

    total = N_MODELS + job.samples  # one bar: the symbolic models built, then the states checked
    job.check = run_check(job.robot, job.samples, 0, progress=lambda n: job.progress.count(N_MODELS + n, total),
                          building=lambda k: job.progress.count(k, total)).as_dict()
    try:  # MuJoCo and iDynTree as references, when installed; a failure here is shown, the terms are kept
        job.check = {**job.check, **cross_library(job.robot)}
    except Exception as e:
        job.check = {**job.check, "cross_library_passed": False, "cross_library_note": f"could not run: {type(e).__name__}: {e}"}
    return rs.terms_section(job.check)


def _grf_section(job: _Job) -> Section:
    from quadruped_dyn.experiment.gait import gait_posture
    from quadruped_dyn.report import sections as rs
    from quadruped_dyn.report.figures import footprint_figure

    posture, cases, feet = grf_posture(job.robot, gait_posture(job.robot), FRICTION_MU)
    fig = figure(footprint_figure(feet, cases), "free and unbalanced directions on the footprint",
                 "rank-5 systems of the paper's model at the gait posture: free and unbalanced directions")
    return rs.grf_section(job.check, posture, fig)


def _reduced_section(job: _Job) -> Section:
    from quadruped_dyn.experiment.gait import gait_posture
    from quadruped_dyn.report import sections as rs

    return rs.reduced_section(reduced_rows(job.robot, gait_posture(job.robot), job.progress.count), "the gait posture")


def _experiment_section(job: _Job) -> Section:
    from quadruped_dyn.experiment.paper_experiment import joint_names  # the labels the validation JSON is keyed by
    from quadruped_dyn.report import sections as rs

    validations, plots = experiment(job.robot, job.target, job.progress)
    return rs.experiment_section(validations, joint_names(job.robot), plots)


def _c_section(job: _Job) -> Section:
    from quadruped_dyn.report import sections as rs

    gen, files = generated_c(job.robot, job.target, job.progress.count)
    gen["directory"] = str((job.folder or job.target) / C_FOLDER)  # where they are published, with the page
    if job.fast:
        return rs.generated_c_section(gen, None, "skipped with --fast")
    from quadruped_dyn.bench.timing import run_bench

    # the cross builds (cached; docs/embedded.md) only with --footprint: minutes of compiling on a cold cache
    gen["embedded"] = embedded_footprint(job.robot, job.target / C_FOLDER, measure=job.footprint)
    bench = run_bench(job.robot, checked_c=files, parametric=True)  # the files just checked; the family's too
    return rs.generated_c_section(gen, bench.as_dict())


def _symbolic_section(job: _Job) -> Section:
    from quadruped_dyn.report import sections as rs
    from quadruped_dyn.report.figures import sparsity_figure

    formulas, note, sizes, patterns = symbolic_data(job.robot)
    fig = figure(sparsity_figure(patterns), "sparsity of every term",
                 "structural nonzeros: matrix outputs as they are, vector outputs as their Jacobian w.r.t. all inputs")
    return rs.symbolic_section(formulas, note, sizes, fig)


def _notebooks_section(job: _Job) -> Section:
    """The notebooks, each executed by whichever process gets to it first: the warm process, after
    its builds, from the front of the list; here, from the back, one at a time, each one it has not
    started (its task cancelled), so both processes execute notebooks until none is left; all of
    them here without the warm process, or if it died. A bar counts them."""
    from quadruped_dyn.report import sections as rs

    paths, note = notebook_list(job.robot)
    if not paths:
        return rs.notebooks_section(None, note)
    bar = job.progress.bar(len(paths), "notebooks")
    ahead: list[Future[dict[str, Any]] | None] = [*job.notebooks_ahead] if job.notebooks_ahead else [None] * len(paths)
    # from the back, one at a time, until one is the warm process's (started: it takes them in order,
    # so every one before it is too); taking all at once left the warm process idle once its builds were done
    mine: set[int] = set()
    rendered: dict[int, dict[str, Any]] = {}
    for k in reversed(range(len(paths))):
        future = ahead[k]
        if not (future is None or future.cancel()):
            break
        mine.add(k)
        rendered[k] = executed_notebook(paths[k])
        bar.advance(1)
    for k, future in enumerate(ahead):
        if k in mine or future is None:
            continue
        try:
            rendered[k] = future.result()
        except BrokenProcessPool:  # the warm process died (its work was only a head start)
            rendered[k] = executed_notebook(paths[k])
        bar.advance(1)
    return rs.notebooks_section([rendered[k] for k in range(len(paths))], "")
