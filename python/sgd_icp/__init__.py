"""SGD-ICP point-cloud registration (Maken, Ramos, Ott, ICRA 2019) with NumPy in and results out.

>>> import sgd_icp
>>> source = sgd_icp.read_points("scan1.pcd")          # (N, 3) float32, metres
>>> reference = sgd_icp.read_points("scan0.pcd")
>>> result = sgd_icp.register(source, reference)       # default settings
>>> result.T_reference_source                          # (4, 4) float64: p_ref = R @ p_src + t
>>> result = sgd_icp.register(source, reference, method="gicp")   # batch GICP

Open3D clouds (open3d.geometry.PointCloud, open3d.t.geometry.PointCloud) are accepted wherever
arrays are, without importing open3d here; sgd_icp.distributed registers many pairs on a Dask
cluster (docs/distributed.md).

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
    FrameReport,
    FormatError,
    InvalidInputError,
    InvalidSettingsError,
    IoError,
    KernelType,
    Localizer,
    NeighborhoodSettings,
    Odometry,
    OptimizerSettings,
    OptimizerType,
    PoseMode,
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
    depth_to_points,
    estimate_covariances,
    estimate_normals,
    random_downsample,
    read_pairs,
    read_depth_image,
    read_point_cloud,
    read_points,
    read_transform,
    register,
    register_sweep,
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
    "FrameReport",
    "FormatError",
    "InvalidInputError",
    "InvalidSettingsError",
    "IoError",
    "KernelType",
    "Localizer",
    "NeighborhoodSettings",
    "Odometry",
    "OptimizerSettings",
    "OptimizerType",
    "PoseMode",
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
    "depth_to_points",
    "estimate_covariances",
    "estimate_normals",
    "random_downsample",
    "read_pairs",
    "read_depth_image",
    "read_point_cloud",
    "read_points",
    "read_transform",
    "register",
    "register_sweep",
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

from . import _pickle  # noqa: E402 - the settings classes pickle (multiprocessing, Dask)

_pickle.register()
del _pickle
