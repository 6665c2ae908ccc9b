"""``quadruped-dyn report``: one self-contained HTML page of everything the toolkit knows about
a robot (``<out>/<robot>/report.html``), with its files beside it (the experiment's plots and
JSON, the generated C).

Each section is gathered by a function here, from the toolkit's public APIs, and rendered by
``report_sections`` from plain data (the same dicts the commands print as JSON). A section
whose gathering raises shows FAIL with the message; the page is written anyway.

Conventions of the numbers shown: trunk frame b (x forward, y left, z up), world z up;
joint order FL, FR, BL, BR x (HAA, HFE, KFE); quaternions (x, y, z, w); a = vdot, i.e. the
trunk's spatial acceleration, as everywhere in the project.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.model.robot import ROBOT_NAMES, robot_path
from quadruped_dyn.report.gather import (
    CHECK_SAMPLES,
    FRICTION_MU,
    experiment,
    generated_c,
    grf_posture,
    leg_points,
    load_with_warnings,
    notebooks,
    reduced_rows,
    robot_data,
    symbolic_data,
    versions,
)
from quadruped_dyn.report.html import Section, figure, page


class Progress:
    """One line per step on stderr: ``[k/N] what ... 12.3 s``; on a terminal, a step with
    a count (``count(n, total)``) shows it as it goes."""

    def __init__(self, total: int, enabled: bool = True) -> None:
        self.total, self.k, self.enabled = total, 0, enabled
        self.line = ""
        self.live = enabled and sys.stderr.isatty()

    def step(self, what: str) -> Callable[[], None]:
        self.k += 1
        start = time.perf_counter()
        self.line = f"[{self.k}/{self.total}] {what} ..."
        if self.enabled:
            print(self.line, end="", file=sys.stderr, flush=True)

        def done() -> None:
            if self.enabled:
                again = f"\r{self.line}\x1b[K" if self.live else ""  # rewrite the line a count has extended
                print(f"{again} {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)

        return done

    def count(self, n: int, total: int) -> None:
        if self.live:
            print(f"\r{self.line} {n}/{total}", end="", file=sys.stderr, flush=True)


def prepare(robot_arg: str, out: str | Path) -> tuple[Path, Path]:
    """Validate the arguments before any work: (URDF path, the robot's output directory).
    InputError for an unknown robot or an output directory that cannot be written."""
    urdf = robot_path(robot_arg)
    name = robot_arg if robot_arg in ROBOT_NAMES else urdf.stem  # as load_robot names it
    target = Path(out) / name
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
        lines.append(f"wrote {self.path}")
        return "\n".join(lines)


def _failed(key: str, title: str, e: Exception) -> Section:
    message = f"{type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else ''}"
    return Section(key, title, "FAIL", message[:160], f'<p class="warn">Could not build this section: {message}</p>')


def build_report(robot_arg: str = "paper", out: str | Path = "results", fast: bool = False,
                 samples: int = CHECK_SAMPLES, with_notebooks: bool = True, show_progress: bool = True) -> ReportResult:
    """Write ``<out>/<robot>/report.html`` (see the module docstring); ``fast`` skips the
    benchmark. Arguments are validated (InputError) before any work."""
    import matplotlib

    matplotlib.use("Agg")  # figures go into the page, never to a window
    from quadruped_dyn.report import sections as rs
    from quadruped_dyn.report.figures import footprint_figure, sparsity_figure, stick_figure

    _, target = prepare(robot_arg, out)
    progress = Progress(9, show_progress)
    sections: list[Section] = []

    def attempt(key: str, title: str, build: Callable[[], Section]) -> None:
        try:
            sections.append(build())
        except Exception as e:  # one section failing must not lose the others: it is reported on the page
            sections.append(_failed(key, title, e))

    done = progress.step(f"loading {robot_arg}")
    robot, urdf_warnings = load_with_warnings(robot_arg)
    from quadruped_dyn.experiment.gait import gait_posture

    def robot_section() -> Section:
        chains = leg_points(robot, robot.standing_q)
        fig = figure(stick_figure(chains, f"{robot.name} at its standing posture"), "stick figure of the robot",
                     "legs and feet at robot.standing_q, trunk level, lowest foot on the ground")
        return rs.robot_section(robot_data(robot, urdf_warnings), fig)

    attempt("robot", "The robot", robot_section)
    done()

    done = progress.step(f"every term against Pinocchio ({samples} random states)")
    check: dict[str, Any] | None = None
    try:
        from quadruped_dyn.checks.terms import run_check

        check = run_check(robot, samples, 0, progress=lambda n: progress.count(n, samples)).as_dict()
        sections.append(rs.terms_section(check))
    except Exception as e:
        sections.append(_failed("terms", "Every term against Pinocchio", e))
    done()

    done = progress.step("GRF systems")

    def grf_section() -> Section:
        posture, cases, feet = grf_posture(robot, gait_posture(robot), FRICTION_MU)
        fig = figure(footprint_figure(feet, cases), "free and unbalanced directions on the footprint",
                     "rank-5 systems of the paper's model at the gait posture: free and unbalanced directions")
        return rs.grf_section(check, posture, fig)

    attempt("grf", "Ground-reaction-force systems", grf_section)
    done()

    done = progress.step("reduced model of every stance set")
    attempt("reduced", "Reduced model per stance set",
            lambda: rs.reduced_section(reduced_rows(robot, gait_posture(robot)), "the gait posture"))
    done()

    done = progress.step("the paper's experiment: trot and static walk")
    def experiment_section() -> Section:
        from quadruped_dyn.experiment.paper_experiment import joint_names  # the labels the validation JSON is keyed by

        validations, plots = experiment(robot, target)
        return rs.experiment_section(validations, joint_names(robot), plots)

    attempt("experiment", "The paper's experiment: trot and static walk", experiment_section)
    done()

    done = progress.step("generated C" + ("" if fast else " and the benchmark"))

    def c_section() -> Section:
        gen = generated_c(robot, target)
        if fast:
            return rs.generated_c_section(gen, None, "skipped with --fast")
        from quadruped_dyn.bench.timing import run_bench

        return rs.generated_c_section(gen, run_bench(robot).as_dict())

    attempt("c", "Generated C", c_section)
    done()

    done = progress.step("symbolic terms")

    def symbolic_section() -> Section:
        formulas, note, sizes, patterns = symbolic_data(robot)
        fig = figure(sparsity_figure(patterns), "sparsity of every term",
                     "structural nonzeros: matrix outputs as they are, vector outputs as their Jacobian w.r.t. all inputs")
        return rs.symbolic_section(formulas, note, sizes, fig)

    attempt("symbolic", "Symbolic terms", symbolic_section)
    done()

    done = progress.step("notebooks")
    if with_notebooks:
        attempt("notebooks", "Notebooks, executed", lambda: rs.notebooks_section(*notebooks(robot)))
    else:
        sections.append(rs.notebooks_section(None, "not executed for this page"))
    done()

    done = progress.step("versions, writing the page")
    sections.append(rs.versions_section(versions()))
    path = target / "report.html"
    subtitle = (f"{robot.urdf} — built {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC by quadruped-dyn report"
                + (" --fast" if fast else ""))
    path.write_text(page(f"quadruped_dyn report: {robot.name}", subtitle, sections))
    done()
    return ReportResult(path, sections)
