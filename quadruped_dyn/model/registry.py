"""The built-in robots: their names and where their URDFs are (the paper's, package data; six from
example-robot-data), and a name or a path resolved to a URDF file."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.model.paper_robot import URDF_PATH

#: Built-in robots: the paper's (generated, package data) and six from example-robot-data.
_ERD_FILES = {
    "solo12": "solo_description/robots/solo12.urdf",
    "go2": "go2_description/urdf/go2.urdf",
    "go1": "go1_description/urdf/go1.urdf",
    "a1": "a1_description/urdf/a1.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
}
ROBOT_NAMES: tuple[str, ...] = ("paper", *_ERD_FILES)


def example_robot_data_dir() -> Path:
    """The robots/ folder of the installed example-robot-data package."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as e:
        raise InputError("example-robot-data is not installed; expected it installed (pip install example-robot-data)") from e
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))


def builtin_path(name: str) -> Path:
    """The URDF of the built-in robot ``name`` (a key of ``ROBOT_NAMES``)."""
    return URDF_PATH if name == "paper" else example_robot_data_dir() / _ERD_FILES[name]


def robot_path(name_or_path: str | Path) -> Path:
    """Resolve a built-in robot name or a URDF path to an existing file (absolute, symlinks resolved)."""
    if not isinstance(name_or_path, (str, Path)):
        raise InputError(f"robot {name_or_path!r} is a {type(name_or_path).__name__}; expected a built-in name "
                         f"({', '.join(ROBOT_NAMES)}) or the path of a URDF file")
    key = str(name_or_path)
    if key in ROBOT_NAMES:
        path = builtin_path(key)
        if not path.is_file():
            raise InputError(f"the URDF of built-in robot '{key}' is missing at '{path}'; expected the installed "
                             "package's file (reinstall quadruped_dyn / example-robot-data)")
        return path.resolve()
    path = Path(key)
    if not path.is_file():
        what = "not a regular file" if path.exists() else "no such file"
        raise InputError(f"{what}: '{printable(key)}'; expected a URDF path or one of: {', '.join(ROBOT_NAMES)}")
    return path.resolve()
