"""Everything measured about a generated directory for embedding (docs/embedded.md): each
function's caller memory (its compiled ``_work`` entry and signature), its code size and worst-case stack on Cortex-M7 and
Cortex-M4F at -Os and -O2 (``codegen.footprint``, cross builds, cached), against the issue's
budgets. ``codegen --json`` prints it; the report shows it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from quadruped_dyn.codegen.file_names import REDUCED_STANCE_SETS, feet_suffix, robot_stem
from quadruped_dyn.codegen.footprint import MEASURED_BUILDS, robot_footprint
from quadruped_dyn.codegen.work_memory import WorkMemory, work_memory
from quadruped_dyn.model.robot import Robot


def embedded_summary(robot: Robot, directory: Path, footprint: bool = True,
                     builds: tuple[tuple[str, str], ...] = MEASURED_BUILDS) -> dict[str, Any]:
    """JSON-ready summary of ``directory`` (a ``codegen`` output of ``robot``), the footprint
    measured on ``builds`` ((Cortex-M target, cflags) pairs)."""
    name = robot_stem(robot.name)
    memory = library_work_memory(robot)
    functions = [{"name": n, "sz_arg": m.sz_arg, "sz_res": m.sz_res, "sz_iw": m.sz_iw, "sz_w": m.sz_w,
                  "in_reals": m.n_in, "out_reals": m.n_out, "caller_bytes_double": m.bytes(8),
                  "caller_bytes_float": m.bytes(4)} for n, m in memory.items()]
    stances = [feet_suffix(s) for s in REDUCED_STANCE_SETS]
    return {"robot": robot.name, "directory": str(directory), "functions": functions,
            "footprint": robot_footprint(Path(directory), list(memory), name, stances, builds) if footprint
            else {"skipped": "not requested"}}


def library_work_memory(robot: Robot) -> dict[str, WorkMemory]:
    """Every generated function's WorkMemory, in the header's order: iw and w from the compiled library's ``_work``
    entries (the sizes its header states), the rest from the Functions (``work_memory``)."""
    import ctypes

    from quadruped_dyn.codegen.emit import library_functions
    from quadruped_dyn.codegen.library import compiled_library, work_sizes_of

    lib = ctypes.CDLL(str(compiled_library(robot).path))
    return {f.name(): work_memory(f, *work_sizes_of(lib, f.name())[2:]) for f in library_functions(robot)}
