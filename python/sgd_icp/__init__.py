"""SGD-ICP point-cloud registration (Maken, Ramos, Ott, ICRA 2019) with NumPy in and results out.

>>> import sgd_icp
>>> source = sgd_icp.read_points("scan1.pcd")          # (N, 3) float32, metres
>>> reference = sgd_icp.read_points("scan0.pcd")
>>> result = sgd_icp.register(source, reference)       # default settings
>>> result.T_reference_source                          # (4, 4) float64: p_ref = R @ p_src + t
>>> result = sgd_icp.register(source, reference, method="gicp")   # batch GICP

See docs/python.md for the methods, the settings, the keyword overrides, preprocessing and the
errors.
"""

from ._core import (
    BatchSettings,
    ConvergenceSettings,
    CostType,
    Distance,
    DistanceUnit,
    Error,
    FormatError,
    InvalidInputError,
    InvalidSettingsError,
    IoError,
    KernelType,
    NeighborhoodSettings,
    OptimizerSettings,
    OptimizerType,
    ReadResult,
    ReferenceIndex,
    RefinementSettings,
    RegistrationResult,
    ScalingOrigin,
    Settings,
    Trace,
    UncertaintySettings,
    UncertaintyType,
    __version__,
    estimate_covariances,
    estimate_normals,
    random_downsample,
    read_point_cloud,
    read_points,
    register,
    rotation_error_euler_sum,
    rotation_error_geodesic,
    translation_error,
    voxel_downsample,
    write_points,
)

__all__ = [
    "BatchSettings",
    "ConvergenceSettings",
    "CostType",
    "Distance",
    "DistanceUnit",
    "Error",
    "FormatError",
    "InvalidInputError",
    "InvalidSettingsError",
    "IoError",
    "KernelType",
    "NeighborhoodSettings",
    "OptimizerSettings",
    "OptimizerType",
    "ReadResult",
    "ReferenceIndex",
    "RefinementSettings",
    "RegistrationResult",
    "ScalingOrigin",
    "Settings",
    "Trace",
    "UncertaintySettings",
    "UncertaintyType",
    "__version__",
    "estimate_covariances",
    "estimate_normals",
    "random_downsample",
    "read_point_cloud",
    "read_points",
    "register",
    "rotation_error_euler_sum",
    "rotation_error_geodesic",
    "translation_error",
    "voxel_downsample",
    "write_points",
]

# Public names report the package, not the private extension module (reprs, help(), pickling by
# reference).
for _name in __all__:
    _obj = globals()[_name]
    if isinstance(_obj, type) and _obj.__module__ == "sgd_icp._core":
        try:
            _obj.__module__ = __name__
        except (AttributeError, TypeError):  # pragma: no cover - immutable type
            pass
del _name, _obj
