"""Files in and out, by concern.

* :mod:`~armcal.files.common` -- one error form, text from a file or stdin, TOML, numbers;
* :mod:`~armcal.files.paths` -- output paths that destroy nothing, atomic writes;
* :mod:`~armcal.files.robots` -- planar robot and truth TOML, the built-in robots;
* :mod:`~armcal.files.spatial` -- spatial robot and truth files (URDF, DH tables);
* :func:`load_robot` -- a robot of any family (:mod:`armcal.families`);
* :mod:`~armcal.files.tables` -- plan, measurement and program CSV;
* :mod:`~armcal.files.calibration` -- the calibration JSON, written and read.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from ..families.registry import RobotSpec, load_robot
    from .calibration import (
        CALIBRATION_FORMAT,
        calibration_document,
        read_calibration,
        robot_to_dict,
    )
    from .common import STDIO, to_json, write_json
    from .paths import MANIFEST, OutputFolder, atomic_write, check_outputs, write_folder
    from .robots import (
        BUILTIN_ROBOTS,
        COMPLIANCE_TRUTH_KEYS,
        DEFAULT_ROBOT,
        JOINT_SIGMA_MAX_DEG,
        LINK_LENGTH_RANGE_MM,
        RADIAN_LIMIT_BOUND,
        SIGMA_RANGE_MM,
        load_compliance_truth,
        load_planar_robot,
        load_truth,
        unknown_parameter,
    )
    from .spatial import (
        BUILTIN_SPATIAL_ROBOTS,
        is_spatial_robot,
        load_spatial_robot,
        load_spatial_truth,
    )
    from .tables import (
        INSTRUMENT_RANGE,
        LIMIT_TOLERANCE_DEG,
        REACH_MARGIN,
        Measurements,
        Program,
        read_labelled_plan,
        read_loaded_plan,
        read_measurements,
        read_plan,
        read_program,
    )
    from .writers import format_measurements_csv, format_plan_csv, format_program_csv

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            "..families.registry": ("RobotSpec", "load_robot"),
            ".calibration": (
                "CALIBRATION_FORMAT",
                "calibration_document",
                "read_calibration",
                "robot_to_dict",
            ),
            ".common": ("STDIO", "to_json", "write_json"),
            ".paths": (
                "MANIFEST",
                "OutputFolder",
                "atomic_write",
                "check_outputs",
                "write_folder",
            ),
            ".robots": (
                "BUILTIN_ROBOTS",
                "COMPLIANCE_TRUTH_KEYS",
                "DEFAULT_ROBOT",
                "JOINT_SIGMA_MAX_DEG",
                "LINK_LENGTH_RANGE_MM",
                "RADIAN_LIMIT_BOUND",
                "SIGMA_RANGE_MM",
                "load_compliance_truth",
                "load_planar_robot",
                "load_truth",
                "unknown_parameter",
            ),
            ".spatial": (
                "BUILTIN_SPATIAL_ROBOTS",
                "is_spatial_robot",
                "load_spatial_robot",
                "load_spatial_truth",
            ),
            ".tables": (
                "INSTRUMENT_RANGE",
                "LIMIT_TOLERANCE_DEG",
                "REACH_MARGIN",
                "Measurements",
                "Program",
                "read_labelled_plan",
                "read_loaded_plan",
                "read_measurements",
                "read_plan",
                "read_program",
            ),
            ".writers": ("format_measurements_csv", "format_plan_csv", "format_program_csv"),
        },
    )

__all__ = [
    "BUILTIN_ROBOTS",
    "BUILTIN_SPATIAL_ROBOTS",
    "CALIBRATION_FORMAT",
    "COMPLIANCE_TRUTH_KEYS",
    "DEFAULT_ROBOT",
    "INSTRUMENT_RANGE",
    "JOINT_SIGMA_MAX_DEG",
    "LIMIT_TOLERANCE_DEG",
    "LINK_LENGTH_RANGE_MM",
    "MANIFEST",
    "RADIAN_LIMIT_BOUND",
    "REACH_MARGIN",
    "SIGMA_RANGE_MM",
    "STDIO",
    "Measurements",
    "OutputFolder",
    "Program",
    "RobotSpec",
    "atomic_write",
    "calibration_document",
    "check_outputs",
    "format_measurements_csv",
    "format_plan_csv",
    "format_program_csv",
    "is_spatial_robot",
    "load_compliance_truth",
    "load_planar_robot",
    "load_robot",
    "load_spatial_robot",
    "load_spatial_truth",
    "load_truth",
    "read_calibration",
    "read_labelled_plan",
    "read_loaded_plan",
    "read_measurements",
    "read_plan",
    "read_program",
    "robot_to_dict",
    "to_json",
    "unknown_parameter",
    "write_folder",
    "write_json",
]
