"""Type stubs of sgd_icp._core, the C++ core of sgd_icp (every public name is re-exported by sgd_icp).

Units: metres for points, transforms and distances in metres; "scaled" units are fractions of the
largest side of the joint bounding box of both clouds (the paper's [0, 1] space); angles in
radians.
"""

import enum
import os
from typing import Any, Literal, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, os.PathLike[str]]
_Points = Union[npt.ArrayLike, Any]
"""An (N, 3) float32 or float64 array of points in metres, any memory layout, or an Open3D
PointCloud (open3d.geometry.PointCloud or open3d.t.geometry.PointCloud)."""
_Transform = npt.ArrayLike
"""A (4, 4) rigid transform, metres."""
_OptimizerName = Union["OptimizerType", str]
_OriginName = Union["ScalingOrigin", str]
_CostName = Union["CostType", str]
_KernelName = Union["KernelType", str]
_UnitName = Union["DistanceUnit", str]
_DistanceValue = Union[float, "Distance"]
_MethodName = Literal["sgd", "sgd-point", "sgd-plane", "sgd-gicp", "icp", "icp-plane", "gicp"]
_UncertaintyName = Union["UncertaintyType", Literal["none", "laplace", "sgld", "svgd"]]

# ---- errors


class Error(Exception):
    """Base class of every error the sgd_icp library raises."""


class InvalidInputError(Error, ValueError):
    """Input the method cannot work with: a wrong array shape or dtype, an empty or all-NaN cloud,
    fewer points than a mini-batch, a non-rigid initial transform. A ValueError.
    """


class InvalidSettingsError(Error, ValueError):
    """A setting out of range or contradicting another. A ValueError."""


class FormatError(Error, ValueError):
    """A file whose content is not valid for its format; the message names the file and the line or
    byte where it broke. A ValueError.
    """


class IoError(Error, OSError):
    """A file that cannot be opened, read or written; the message names the path and the system's
    reason. An OSError.
    """


# ---- settings


class DistanceUnit(enum.Enum):
    """Unit of a Distance."""

    metres = 0
    """metres"""
    scaled = 1
    """fractions of the largest side of the joint bounding box of both clouds (the paper's [0, 1]
    space)
    """


class OptimizerType(enum.Enum):
    """Step rule of the paper's eq. 3."""

    sgd = 0
    """fixed step (the paper's vanilla SGD, alpha = 2)"""
    momentum = 1
    """heavy-ball momentum"""
    rmsprop = 2
    """RMSProp"""
    adam = 3
    """Adam (the paper's Adam-SGD; the default)"""
    gauss_newton = 4
    """step pre-conditioned by the averaged mini-batch Gauss-Newton matrix"""


class ScalingOrigin(enum.Enum):
    """Origin of the scaled space, which is also the pivot of the rotation."""

    lower_corner = 0
    """the paper: the lower corner of the joint box, points in [0, 1]"""
    center = 1
    """the centre of the joint box, points in [-0.5, 0.5] (the default)"""


class CostType(enum.Enum):
    """Cost of a pair (source point moved to q, reference point r)."""

    point_to_point = 0
    """|q - r|^2, the paper's (Besl-McKay); the default"""
    point_to_plane = 1
    """(n . (q - r))^2 with the reference normal n (Chen-Medioni)"""
    plane_to_plane = 2
    """e^T (C_r + R C_s R^T)^-1 e with the plane covariances (GICP, Segal et al.)"""


class KernelType(enum.Enum):
    """Robust kernel on each pair's squared residual."""

    none = 0
    """no kernel (least squares); the default"""
    huber = 1
    """Huber"""
    cauchy = 2
    """Cauchy"""
    geman_mcclure = 3
    """Geman-McClure"""
    welsch = 4
    """Welsch"""


class UncertaintyType(enum.Enum):
    """Pose uncertainty of a registration (docs/uncertainty.md)."""

    none = 0
    """no covariance; the default"""
    laplace = 1
    """inverse Gauss-Newton matrix at the optimum times the residual variance"""
    sgld = 2
    """Bayesian ICP: pre-conditioned stochastic gradient Langevin samples"""
    svgd = 3
    """Stein ICP: Stein variational gradient descent particles, clustered into modes"""


class Distance:
    """A length with its unit: metres, or scaled units (1 = the largest side of the joint bounding
    box of both clouds, the paper's [0, 1] space).

    Make one with Distance.metres(v) or Distance.scaled(v).
    """

    value: float
    """The length, in `unit`."""
    unit: DistanceUnit
    """DistanceUnit.metres or DistanceUnit.scaled."""

    def __init__(self, value: float, unit: _UnitName = "scaled") -> None:
        """A distance of `value` in `unit` ('m', 'scaled' or a DistanceUnit; default 'scaled')."""

    @staticmethod
    def metres(value: float) -> Distance:
        """A distance in metres."""

    @staticmethod
    def scaled(value: float) -> Distance:
        """A distance in scaled units (fraction of the largest side of the joint box)."""

    def to_scaled(self, metres_per_unit: float) -> float:
        """The value in scaled units, given the metres per scaled unit (RegistrationResult.scale_m).
        """

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> Distance: ...
    def __deepcopy__(self, memo: Any) -> Distance: ...


class OptimizerSettings:
    """Step rule of eq. 3 and its parameters (Settings.optimizer)."""

    type: OptimizerType
    """Step rule of eq. 3 (sgd: fixed step; gauss-newton: A = inverse of the averaged mini-batch
    Gauss-Newton matrix); also sets the learning rate to the rule's own unless one is given
    (OptimizerType or one of its names). Keyword optimizer=. Default OptimizerType.adam. (That is
    Settings()'s; a OptimizerSettings() of its own has OptimizerType.sgd.)
    """
    learning_rate: float
    """Step size alpha (adaptive rules: a length per step; sgd, momentum: a gradient multiplier;
    gauss-newton: a fraction of the Newton step), scaled units in [1e-06, 10000]. Keyword
    learning_rate=. Default 0.01. (That is Settings()'s; a OptimizerSettings() of its own has
    2.0.)
    """
    damping: float
    """Gauss-Newton step: Levenberg damping, relative to the mean diagonal of the averaged matrix
    (batch methods: the initial Levenberg-Marquardt damping), in [0, 100]. Keyword damping=.
    Default 0.001.
    """

    def __init__(self) -> None: ...
    def validate(self) -> None:
        """Raises InvalidSettingsError (a ValueError) naming the first invalid value."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> OptimizerSettings: ...
    def __deepcopy__(self, memo: Any) -> OptimizerSettings: ...


class ConvergenceSettings:
    """When a stage is stationary: Hotelling's T^2 test on the window's mini-batch gradients and a
    path-efficiency guard, or an absolute tolerance on every step (Settings.convergence).
    """

    window: int
    """Convergence: iterations per test window (a stage ends after a window whose mean mini-batch
    gradient is not significantly non-zero); also the length of the final iterate average, in [8,
    100000]. Keyword window=. Default 20.
    """
    chi2: float
    """Convergence: critical chi-square value (6 dof) of the Hotelling test on the window's mean
    gradient; larger stops earlier, in (0, 1000]. Keyword chi2=. Default 12.59.
    """
    max_path_efficiency: float
    """A stationary window's net displacement over its path length, in (0, 1]. A fixed rule. Default
    0.5.
    """
    translation_tolerance: float
    """Convergence: a window whose steps each move the translation less than this also ends a stage
    (batch methods: an iteration that moves it less converges), scaled units in [0, 0.01].
    Keyword translation_tolerance=. Default 1e-06.
    """
    rotation_tolerance: float
    """Convergence: ... and the angles less than this (sum of |d roll|, |d pitch|, |d yaw|; batch
    methods: rotation angle), rad in [0, 0.01]. Keyword rotation_tolerance=. Default 1e-06.
    """

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> ConvergenceSettings: ...
    def __deepcopy__(self, memo: Any) -> ConvergenceSettings: ...


class RefinementSettings:
    """Refinement stages after the paper's coarse phase: each shrinks d_max to the data and decays
    the step (Settings.refinement).
    """

    stages: int
    """Refinement stages after the first stationary stage (0 = the paper's single phase), in [0,
    100]. Keyword refine_stages=. Default 3.
    """
    step_decay: float
    """Refinement: step-size multiplier per stage, in [0.01, 1]. Keyword step_decay=. Default 0.5.
    """
    distance_factor: float
    """Refinement: new d_max = factor x median correspondence distance (below 1 it would reject most
    pairs: use trim for that), in [1, 1000]. Keyword distance_factor=. Default 3.0.
    """
    min_distance: Distance
    """Refinement: lower bound of d_max, a Distance in [1e-06, 10] scaled units or [1e-06, 1000000]
    m. Keyword min_distance=. Default Distance.scaled(0.0001).
    """
    gauss_newton: bool
    """The refinement stages take Gauss-Newton steps. A fixed rule. Default True."""
    settle_tolerance: float
    """A refinement stage ends the run when its pairs have settled, in [0, 0.99]. A fixed rule.
    Default 0.05.
    """

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> RefinementSettings: ...
    def __deepcopy__(self, memo: Any) -> RefinementSettings: ...


class UncertaintySettings:
    """Pose uncertainty of the result and its sampler and calibration (Settings.uncertainty;
    docs/uncertainty.md).
    """

    method: UncertaintyType
    """Pose uncertainty of the result: none, laplace (sandwich covariance of the re-paired optimum:
    the one to use for a pose graph), sgld (Bayesian ICP: Langevin samples) or svgd (Stein ICP:
    particles, clustered into modes) (UncertaintyType or one of its names). Keyword uncertainty=.
    Default UncertaintyType.none.
    """
    samples: int
    """sgld: samples kept, in [2, 1000000]. Keyword uncertainty_samples=. Default 200."""
    burn_in: int
    """sgld: iterations before the first sample, in [0, 10000000]. A fixed rule. Default 50."""
    thinning: int
    """sgld: iterations per sample, in [1, 10000]. Keyword thinning=. Default 5."""
    step: float
    """sgld: contraction per iteration, in [0.0001, 1]. A fixed rule. Default 0.1."""
    particles: int
    """svgd: particles K, in [1, 10000]. Keyword particles=. Default 32."""
    svgd_iterations: int
    """svgd: iterations, one mini-batch shared by every particle each, in [1, 1000000]. Keyword
    svgd_iterations=. Default 50.
    """
    svgd_step: float
    """svgd: Adam's last step, posterior std in [0.0001, 10]. A fixed rule. Default 0.05."""
    svgd_spread: float
    """svgd: spread of the initial particles around the estimate, in Laplace standard deviations
    (wide values reach other modes), posterior std in [0.001, 1000000000]. Keyword svgd_spread=.
    Default 3.0.
    """
    temper: bool
    """laplace: the sandwich of the re-paired optimum and the grid's share; sgld, svgd: the
    likelihood tempered by the residuals' measured correlation (false: the fixed-pair Hessian
    with independent residuals, as the peers report). Keyword temper=. Default True.
    """
    block_size: Distance
    """Block side of the sandwich estimator, a Distance in [1e-06, 10] scaled units or [1e-06,
    1000000] m. A fixed rule. Default Distance.scaled(0.1).
    """
    softening: float
    """laplace: the curvature's softening to use, 0 = measure it (the secant); (0, 0.1) refused, in
    [0, 1]. A fixed rule. Default 0.0.
    """

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> UncertaintySettings: ...
    def __deepcopy__(self, memo: Any) -> UncertaintySettings: ...


class NeighborhoodSettings:
    """k-nearest neighbourhoods for the normals and covariances of the plane costs
    (Settings.neighborhood).
    """

    k: int
    """Plane costs: neighbours per point (itself included) for normals and covariances, in [3,
    1000]. Keyword neighbors=. Default 20.
    """
    flat_k: int
    """Neighbours of a point whose nearest ones already lie flat (surface variation at most
    flatness): those alone give its normal and covariance; 0 = always k. Settings: 10,
    BatchSettings: 0 (docs/preprocessing.md).
    """
    flatness: float
    """The largest surface variation of a flat neighbourhood, in [0, 1/3]. Default 0.05."""
    num_threads: int
    """Worker threads of the estimation; 0 = all cores (the results are the same for any count).
    Default 0.
    """
    regularize: bool
    """Replace each covariance by the GICP plane model (unitless). Default True."""
    epsilon: float
    """Variance along the normal in the plane model, relative to 1 in the plane, in (0, 1]. Default
    1e-3.
    """
    @property
    def viewpoint(self) -> npt.NDArray[np.float64]:
        """Normals are flipped to face this point, (3,) array, metres. Default (0, 0, 0)."""
    @viewpoint.setter
    def viewpoint(self, value: npt.ArrayLike) -> None: ...

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> NeighborhoodSettings: ...
    def __deepcopy__(self, memo: Any) -> NeighborhoodSettings: ...


class Settings:
    """Every setting of a registration: the C++ sgdicp::SgdSettings, same names and defaults.

    Settings(**overrides) is the measured default (Adam 0.01, refinement) with the flat keyword
    overrides of register() applied; Settings.paper() is the paper's. Attributes can be changed
    in place, nested ones too (s.optimizer.learning_rate = 0.02).
    """

    batch_size: int
    """Mini-batch size m, source points per iteration, in [1, 10000000]. Keyword batch_size=.
    Default 160.
    """
    adapt_small_sources: bool
    """The small-source rules (Settings.paper(): False): a capped mini-batch and Gauss-Newton coarse
    steps for sources of fewer than batch_size x window / 2 points.
    """
    max_correspondence_distance: Distance
    """Correspondence rejection distance d_max, a Distance in [1e-06, 10] scaled units or [1e-06,
    1000000] m. Keyword max_distance=. Default Distance.scaled(0.5).
    """
    optimizer: OptimizerSettings
    """OptimizerSettings. Default Adam with learning rate 0.01."""
    convergence: ConvergenceSettings
    """ConvergenceSettings."""
    refinement: RefinementSettings
    """RefinementSettings."""
    uncertainty: UncertaintySettings
    """UncertaintySettings. Default: no uncertainty."""
    cost: CostType
    """Cost of a pair in every stage (a coarse-cost given too sets the first stage's):
    point-to-point (the paper), point-to-plane or plane-to-plane (GICP) (CostType or one of its
    names). Keyword cost=. Default CostType.point_to_plane.
    """
    coarse_cost: CostType
    """Cost of the first (coarse) stage when refinement stages follow (the refinement stages and the
    result use the method's cost): point-to-point keeps the paper's wide basin (CostType or one
    of its names). Keyword coarse_cost=. Default CostType.point_to_point.
    """
    kernel: KernelType
    """Robust kernel on the pair residuals (KernelType or one of its names). Keyword kernel=.
    Default KernelType.none.
    """
    kernel_scale: Distance
    """Kernel scale c, the residual size where down-weighting starts, a Distance in [1e-06, 10]
    scaled units or [1e-06, 1000000] m. Keyword kernel_scale=. Default Distance.scaled(0.01).
    """
    trim_ratio: float
    """Keep only this fraction of the pairs (per mini-batch for SGD, per iteration for batch
    methods), the closest ones: trimmed ICP for partial overlap, in [0.01, 1]. Keyword trim=.
    Default 1.0.
    """
    neighborhood: NeighborhoodSettings
    """NeighborhoodSettings for the normals and covariances of the plane costs."""
    scaling_origin: ScalingOrigin
    """Origin of the scaled space and pivot of the rotation (lower-corner, also spelled corner: the
    paper, points in [0, 1]; center: points in [-0.5, 0.5]) (ScalingOrigin or one of its names).
    Keyword scaling_origin=. Default ScalingOrigin.center.
    """
    max_iterations: int
    """Iteration limit (mini-batches); reaching it reports 'not converged', in [1, 1000000000].
    Keyword max_iterations=. Default 4000.
    """
    seed: int
    """Seed of the mini-batch sampler (same seed, same result), in [0, 2^64-1]. Keyword seed=.
    Default 2019.
    """
    average_iterates: bool
    """Return the mean of the window iterates of the final stage's stationary window (true) or the
    last iterate (false). Keyword average=. Default True.
    """
    evaluation_points: int
    """Source points (spread evenly) used for the final inlier ratio and RMSE, 0 = all, in [0,
    4294967295]. Keyword evaluation_points=. Default 2000.
    """
    record_trace: bool
    """Record a per-iteration trace in the result. Keyword record_trace=. Default False."""
    robust_scaling: bool
    """Scale from the bulk of each cloud, not hostage to a few far points (Settings.paper(): False,
    the bounding box of every point). Default True.
    """
    num_threads: int
    """Threads of one registration (its voxel grid passes, KD-tree build, for the SGD plane costs
    the grid's reference normals, the SGD mini-batches' queries and the final statistics' on a
    second thread), 0 = every core; the result is the same for any count, in [0, 1024]. Keyword
    threads=. Default 1.
    """
    voxel_size_m: float
    """Thin both clouds to one point (the centroid) per voxel of this side before registering
    (timed), 0 = the grid --downsample-to chooses, m in [0, 1000000]. Keyword voxel_size=.
    Default 0.0.
    """
    downsample_to: int
    """Without --voxel-size: the voxel grid that keeps about this many points of the reference
    (chosen from the data, +-15 %), applied to both clouds; clouds with at most this many points,
    or with normals or covariances given, are used as they are; 0 = no downsampling, in [0,
    4294967295]. Keyword downsample_to=. Default 20000.
    """

    def __init__(
        self,
        *,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        uncertainty: _UncertaintyName = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
    ) -> None:
        """The default settings with the flat keyword overrides applied (see register())."""

    @staticmethod
    def paper(
        optimizer: _OptimizerName = "sgd",
        *,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        uncertainty: _UncertaintyName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
    ) -> Settings:
        """The paper's settings: m = 160, d_max = 0.5 scaled, fixed step alpha = 2 ('sgd') or Adam
        0.01 ('adam'), no refinement, the last iterate, the lower-corner scaling origin; then the
        keyword overrides.
        """

    def replace(
        self,
        *,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        uncertainty: _UncertaintyName = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
    ) -> Settings:
        """A copy with the flat keyword overrides of register() applied."""

    def validate(self) -> None:
        """Raises InvalidSettingsError (a ValueError) naming the first invalid setting."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> Settings: ...
    def __deepcopy__(self, memo: Any) -> Settings: ...


class BatchSettings:
    """Settings of the batch methods (register(method='icp' | 'icp-plane' | 'gicp')): the C++
    sgdicp::BatchSettings, same names and defaults. Every iteration pairs all source points with
    their nearest reference point within d_max, then takes the closed-form SVD step
    (point-to-point) or one damped Gauss-Newton step (the plane costs).

    BatchSettings(**overrides) is the default (point-to-point) with the batch keyword overrides
    of register() applied (max_distance, max_distance_unit, max_iterations, kernel, kernel_scale,
    trim, neighbors, damping, translation_tolerance, rotation_tolerance, evaluation_points,
    cost).
    """

    cost: CostType
    """Cost of a pair: point-to-point (the paper), point-to-plane or plane-to-plane (GICP) (CostType
    or one of its names). Keyword cost=. Default CostType.point_to_point.
    """
    max_correspondence_distance: Distance
    """Correspondence rejection distance d_max, a Distance in [1e-06, 10] scaled units or [1e-06,
    1000000] m. Keyword max_distance=. Default Distance.scaled(0.05).
    """
    kernel: KernelType
    """Robust kernel on the pair residuals (KernelType or one of its names). Keyword kernel=.
    Default KernelType.none.
    """
    kernel_scale: Distance
    """Kernel scale c, the residual size where down-weighting starts, a Distance in [1e-06, 10]
    scaled units or [1e-06, 1000000] m. Keyword kernel_scale=. Default Distance.scaled(0.01).
    """
    trim_ratio: float
    """Keep only this fraction of the pairs (per mini-batch for SGD, per iteration for batch
    methods), the closest ones: trimmed ICP for partial overlap, in [0.01, 1]. Keyword trim=.
    Default 1.0.
    """
    max_iterations: int
    """Iteration limit (passes over the source); reaching it reports 'not converged', in [1,
    1000000000]. Keyword max_iterations=. Default 100.
    """
    translation_tolerance: float
    """Converged when an iteration moves the translation less than this ..., scaled units in [0,
    0.01]. Keyword translation_tolerance=. Default 1e-05.
    """
    rotation_tolerance: float
    """... and the rotation less than this (rotation angle), rad in [0, 0.01]. Keyword
    rotation_tolerance=. Default 1e-05.
    """
    initial_damping: float
    """icp-plane, gicp: initial Levenberg-Marquardt damping, relative to the mean diagonal of J^T J;
    0 = Gauss-Newton, in [0, 100]. Keyword damping=. Default 1e-06.
    """
    neighborhood: NeighborhoodSettings
    """NeighborhoodSettings for the normals and covariances of the plane costs."""
    evaluation_points: int
    """Source points (spread evenly) used for the final inlier ratio and RMSE, 0 = all, in [0,
    4294967295]. Keyword evaluation_points=. Default 2000.
    """
    robust_scaling: bool
    """Scale from the bulk of each cloud, not hostage to a few far points. Default True."""
    num_threads: int
    """Threads of one registration (its voxel grid passes, KD-tree build, for the SGD plane costs
    the grid's reference normals, the SGD mini-batches' queries and the final statistics' on a
    second thread), 0 = every core; the result is the same for any count, in [0, 1024]. Keyword
    threads=. Default 1.
    """
    voxel_size_m: float
    """Thin both clouds to one point (the centroid) per voxel of this side before registering
    (timed), 0 = the grid --downsample-to chooses, m in [0, 1000000]. Keyword voxel_size=.
    Default 0.0.
    """
    downsample_to: int
    """Without --voxel-size: the voxel grid that keeps about this many points of the reference
    (chosen from the data, +-15 %), applied to both clouds; clouds with at most this many points,
    or with normals or covariances given, are used as they are; 0 = no downsampling, in [0,
    4294967295]. Keyword downsample_to=. Default 0.
    """
    record_trace: bool
    """Record a per-iteration trace in the result. Keyword record_trace=. Default False."""

    def __init__(
        self,
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
    ) -> None:
        """The default settings (point-to-point ICP) with the batch keyword overrides applied."""

    @staticmethod
    def icp(
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
    ) -> BatchSettings:
        """Point-to-point ICP (Besl-McKay; closed-form SVD step), then the keyword overrides."""

    @staticmethod
    def icp_plane(
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
    ) -> BatchSettings:
        """Point-to-plane ICP (Chen-Medioni; Levenberg-Marquardt step), then the keyword overrides.
        """

    @staticmethod
    def gicp(
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
    ) -> BatchSettings:
        """Plane-to-plane GICP (Segal et al.; Levenberg-Marquardt step), then the keyword overrides.
        """

    def replace(
        self,
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
    ) -> BatchSettings:
        """A copy with the batch keyword overrides applied."""

    def validate(self) -> None:
        """Raises InvalidSettingsError (a ValueError) naming the first invalid setting."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> BatchSettings: ...
    def __deepcopy__(self, memo: Any) -> BatchSettings: ...


# The settings table's keywords (keyword, kind, enum class name of a choice) for
# python/tools/stub_signatures.py, which writes the keyword parameters of this stub from them.
def _settings_keywords(
    solver: Literal["sgd", "batch", "odometry", "global"],
) -> list[tuple[str, str, str | None]]: ...


# ---- registration


class ReferenceIndex:
    """A KD-tree over a reference cloud, built once and reused by any number of registrations, also
    from several threads at once (queries are read-only).
    """

    def __init__(
        self,
        points: _Points,
        *,
        normals: npt.ArrayLike | None = None,
        leaf_size: int = 24,
        cost: _CostName = "point-to-point",
        neighborhood: NeighborhoodSettings | None = None,
        threads: int = 1,
    ) -> None:
        """Builds the tree over an (N, 3) float32/float64 array of points in metres (copied once
        into float32 storage; rows with a NaN or infinite coordinate are dropped and counted in
        non_finite_dropped), or over an Open3D PointCloud (legacy or tensor; its normals too when
        it has them). normals: (N, 3) unit normals, one per row of points, default None; the
        point-to-plane cost uses them instead of estimating its own. leaf_size: points per
        KD-tree leaf, default 24. threads: threads of the build, default 1, 0 = every core (the
        same tree for any count). cost: the cost the index will serve, default 'point-to-point';
        'point-to-plane' estimates the reference normals (unless given), 'plane-to-plane' the
        covariances, with `neighborhood` (NeighborhoodSettings, default None =
        NeighborhoodSettings(): plain k-nearest neighbourhoods, as the batch methods' defaults;
        pass Settings().neighborhood to give the SGD methods the normals they would estimate
        themselves). The GIL is released during the build. The index never changes afterwards:
        the SGD methods estimate the normals or covariances they use during the run; a batch
        method whose cost needs them raises InvalidInputError when the index lacks them.
        """

    @staticmethod
    def for_registration(
        points: _Points,
        *,
        method: _MethodName = "sgd",
        settings: Settings | BatchSettings | None = None,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        voxel_size: float = ...,
        uncertainty: _UncertaintyName = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        downsample_to: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
        global_feature_points: int = ...,
        global_normal_neighbors: int = ...,
        global_feature_radius: float = ...,
        global_inlier_distance: float = ...,
        global_max_iterations: int = ...,
        global_confidence: float = ...,
        global_hypotheses: int = ...,
        global_distinct_rotation: float = ...,
        global_distinct_translation: float = ...,
        global_refined_hypotheses: int = ...,
        global_fine_distance: float = ...,
        global_ambiguity_ratio: float = ...,
        global_min_score: float = ...,
        global_min_points: int = ...,
    ) -> ReferenceIndex:
        """The index that register(source, points, method=method, settings=settings, **overrides)
        builds for its reference (for a batch method the cost's normals or covariances with the
        settings' neighbourhood), for reuse over many sources with the same arguments: the
        results are the same as passing points each time. points: an array or an Open3D
        PointCloud, as for register(). The global_* keywords of init='global' are checked and
        leave the index as it is. Raises the errors of register() for the method, settings and
        keywords.
        """

    def __len__(self) -> int: ...
    @property
    def points(self) -> npt.NDArray[np.float32] | npt.NDArray[np.float64]:
        """The indexed points: a read-only (N, 3) float32 view (no copy); a float64 copy for
        georeferenced points.
        """
    @property
    def voxel_size_m(self) -> float:
        """The voxel grid the points were thinned with before indexing, metres (0 = indexed as
        given); registrations against the index thin their source on the same grid.
        """
    @property
    def non_finite_dropped(self) -> int:
        """Rows of the input dropped for a NaN or infinite coordinate."""
    @property
    def build_ms(self) -> float:
        """Wall time of the KD-tree build (and of the normals or covariances), milliseconds."""
    @property
    def has_normals(self) -> bool:
        """Whether the reference has normals (built with cost='point-to-plane' or 'plane-to-plane').
        """
    @property
    def has_covariances(self) -> bool:
        """Whether the reference has covariances (built with cost='plane-to-plane')."""
    @property
    def bounding_box(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(min, max) corners of the axis-aligned bounding box, two (3,) float64 arrays, metres."""


class Trace:
    """Per-iteration record of a registration (Settings.record_trace), one array element per iteration.
    """

    @property
    def iteration(self) -> npt.NDArray[np.int64]:
        """(K,) int64, iteration number."""
    @property
    def points_processed(self) -> npt.NDArray[np.int64]:
        """(K,) int64, source points drawn so far."""
    @property
    def T_reference_source(self) -> npt.NDArray[np.float64]:
        """(K, 4, 4) float64, metric pose after each iteration."""
    @property
    def step_size(self) -> npt.NDArray[np.float64]:
        """(K,) float64, effective learning rate of each iteration."""
    @property
    def max_distance_m(self) -> npt.NDArray[np.float64]:
        """(K,) float64, d_max used, metres."""
    @property
    def inliers(self) -> npt.NDArray[np.int64]:
        """(K,) int64, pairs kept in each mini-batch."""
    @property
    def cost(self) -> npt.NDArray[np.float64]:
        """(K,) float64, mini-batch cost F, scaled units^2."""
    def __len__(self) -> int: ...


class PoseMode:
    """One mode of the svgd particles (RegistrationResult.modes; docs/uncertainty.md)."""

    @property
    def weight(self) -> float:
        """Fraction of the particles in this mode."""
    @property
    def mean(self) -> npt.NDArray[np.float64]:
        """(6,) float64: mean theta = (x, y, z, roll, pitch, yaw), metres and radians."""
    @property
    def covariance(self) -> npt.NDArray[np.float64]:
        """(6, 6) float64: covariance of theta in this mode, metres and radians."""


class RegistrationResult:
    """What register() returns: the transform, why it stopped, the work done and the final inlier
    statistics (every field of the C++ RegistrationResult, plus the non-finite rows dropped and
    the KD-tree build time).
    """

    @property
    def T_reference_source(self) -> npt.NDArray[np.float64]:
        """(4, 4) float64, metres: maps source points into the reference frame, p_ref = R @ p_src + t.
        """
    @property
    def converged(self) -> bool:
        """True if the convergence test passed in the last refinement stage (or in one whose pairs
        had settled, RefinementSettings.settle_tolerance).
        """
    @property
    def stop_reason(self) -> str:
        """'converged', 'max_iterations', 'no_correspondences', 'diverged' or 'no_descent'."""
    @property
    def message(self) -> str:
        """One line on why it stopped."""
    @property
    def iterations(self) -> int:
        """Mini-batches (batch methods: passes over the source) processed."""
    @property
    def points_processed(self) -> int:
        """Source points paired (SGD: iterations x batch size)."""
    @property
    def stages(self) -> int:
        """Stationary stages completed."""
    @property
    def evaluated_points(self) -> int:
        """Source points (spread evenly) in the final inlier statistics."""
    @property
    def inliers(self) -> int:
        """Of those, with a reference point within the final d_max."""
    @property
    def inlier_ratio(self) -> float:
        """inliers / evaluated_points."""
    @property
    def inlier_rmse_m(self) -> float:
        """RMS distance of the inliers to their nearest reference point, metres."""
    @property
    def final_max_distance_m(self) -> float:
        """d_max at the end (after refinement), metres."""
    @property
    def scale_m(self) -> float:
        """Metres per scaled unit."""
    @property
    def far_points(self) -> int:
        """Points of both clouds left out of the scale for lying far from the bulk of their cloud
        (robust_scaling); still paired, d_max rejects them.
        """
    @property
    def time_ms(self) -> float:
        """Wall time of the registration, milliseconds (KD-tree build excluded)."""
    @property
    def constraint_ratio(self) -> float:
        """Smallest over largest eigenvalue of the point-to-plane information matrix of the final
        inlier pairs (scaled space); near 0, some motion is not constrained by the data.
        """
    @property
    def degenerate(self) -> bool:
        """constraint_ratio below 0.01: the transform is not trustworthy along some motion (see
        message).
        """
    @property
    def build_ms(self) -> float:
        """Wall time of the KD-tree build (and reference normals/covariances) for an array
        reference, milliseconds (0 for a ReferenceIndex).
        """
    @property
    def voxel_size_m(self) -> float:
        """Side of the voxel grid the source was thinned with before registering, metres (0 = every
        point used).
        """
    @property
    def source_points(self) -> int:
        """Source points registered (after thinning)."""
    @property
    def source_non_finite_dropped(self) -> int:
        """Source rows dropped for a NaN or infinite coordinate."""
    @property
    def reference_points(self) -> int:
        """Reference points indexed (after thinning)."""
    @property
    def reference_non_finite_dropped(self) -> int:
        """Reference rows dropped for a NaN or infinite coordinate."""
    @property
    def trace(self) -> Trace:
        """Per-iteration Trace; empty unless record_trace=True."""
    @property
    def residual_sigma_m(self) -> float:
        """With uncertainty: RMS of the scalar residuals of the pairs at the optimum, metres (sigma
        of the likelihood).
        """
    @property
    def correlation_factor(self) -> float:
        """With uncertainty: kappa, the factor by which the covariance of independent residuals is
        too narrow (block sandwich estimator); the likelihood is tempered by 1/kappa with temper.
        """
    @property
    def effective_samples(self) -> float:
        """With sgld: the effective sample size of its chain, the smallest over the six coordinates
        (Geyer's initial monotone sequence of autocorrelations): how many independent draws its
        samples are worth, and so how precisely their covariance is known (0 for the other
        methods).
        """
    @property
    def softening(self) -> float:
        """With laplace: the factor by which re-pairing softens the fixed pairs' curvature along the
        directions the data hold (1 = not at all; measured by a secant of the re-paired gradient,
        or given by the odometry from its recent frames); the covariance grows by its inverse
        square.
        """
    @property
    def uncertainty_pairs(self) -> int:
        """With uncertainty: pairs of the full-data pass at the optimum."""
    @property
    def uncertainty_ms(self) -> float:
        """With uncertainty: its wall time, milliseconds (included in time_ms)."""
    @property
    def global_init(self) -> bool:
        """True if the start came from the global estimate (init='global', --init global)."""
    @property
    def global_reliable(self) -> bool:
        """Global: False means no reliable global solution (too few points, no structure, an
        ambiguous scene or degenerate geometry; see message): do not use the transform.
        """
    @property
    def global_ambiguous(self) -> bool:
        """Global: the runner-up hypothesis overlaps nearly as much as the winner (a symmetric
        object, a repetitive scene).
        """
    @property
    def global_winner_rank(self) -> int:
        """Global: the winning hypothesis's rank by feature consensus (0 = the most supported)."""
    @property
    def global_hypotheses(self) -> int:
        """Global: distinct hypotheses verified."""
    @property
    def global_score(self) -> float:
        """Global: the winner's overlap, the fraction of source points within 1.5 feature voxels of
        the reference.
        """
    @property
    def global_runner_up_score(self) -> float:
        """Global: the best other hypothesis's overlap (0 = none); near global_score, the scene is
        ambiguous.
        """
    @property
    def global_ms(self) -> float:
        """Global: wall time of the global estimate, milliseconds (included in time_ms)."""
    @property
    def covariance(self) -> npt.NDArray[np.float64]:
        """(6, 6) float64: covariance of theta = (x, y, z, roll, pitch, yaw) of T_reference_source
        (R = Rz(yaw) Ry(pitch) Rx(roll)), metres and radians; zeros unless uncertainty='laplace',
        'sgld' or 'svgd' (svgd: the heaviest mode's; docs/uncertainty.md).
        """
    @property
    def covariance_se3(self) -> npt.NDArray[np.float64]:
        """(6, 6) float64: the same in the tangent space of SE(3), xi = (rho, phi) translation
        first, right perturbation T = T_reference_source @ Exp(xi).
        """
    @property
    def samples(self) -> npt.NDArray[np.float64]:
        """(K, 6) float64: the SGLD samples (sgld) or the particles (svgd) of theta (as covariance);
        (0, 6) otherwise.
        """
    @property
    def sample_mean(self) -> npt.NDArray[np.float64]:
        """(6,) float64: the mean of the samples (zeros without samples)."""
    @property
    def modes(self) -> list[PoseMode]:
        """uncertainty='svgd': the modes of the particles (PoseMode), heaviest first (covariance is
        the first's); empty otherwise.
        """


def register_sweep(
    source: _Points, reference: _Points, times: npt.ArrayLike, init: _Transform | None = None
) -> dict[str, Any]:
    """Registers a sweep measured while the sensor moved (as `sgdicp register --deskew`): source (N,
    3) with each point's time, times (N,) seconds (any origin), to reference (M, 3), from init (a
    (4, 4) pose, or None). The pose and the sensor's constant velocity within the sweep are
    estimated together (docs/registration.md, Moving sensors). Returns a dict: T_reference_source
    (4, 4), the pose at the sweep's middle mid_time (seconds, in the times' clock); velocity
    (6,), m/s then rad/s in the sensor's frame; converged, iterations, message; aligned (N, 3),
    every source point in input order deskewed into the reference frame.
    """

def register(
    source: _Points,
    reference: Union[_Points, ReferenceIndex],
    init: _Transform | Literal["global"] | None = None,
    settings: Settings | BatchSettings | None = None,
    method: _MethodName = "sgd",
    *,
    max_distance: _DistanceValue = ...,
    seed: int = ...,
    threads: int = ...,
    voxel_size: float = ...,
    uncertainty: _UncertaintyName = ...,
    optimizer: _OptimizerName = ...,
    learning_rate: float = ...,
    batch_size: int = ...,
    max_distance_unit: _UnitName = ...,
    max_iterations: int = ...,
    damping: float = ...,
    window: int = ...,
    chi2: float = ...,
    translation_tolerance: float = ...,
    rotation_tolerance: float = ...,
    refine_stages: int = ...,
    step_decay: float = ...,
    distance_factor: float = ...,
    min_distance: _DistanceValue = ...,
    average: bool = ...,
    scaling_origin: _OriginName = ...,
    evaluation_points: int = ...,
    cost: _CostName = ...,
    coarse_cost: _CostName = ...,
    kernel: _KernelName = ...,
    kernel_scale: _DistanceValue = ...,
    trim: float = ...,
    neighbors: int = ...,
    downsample_to: int = ...,
    record_trace: bool = ...,
    uncertainty_samples: int = ...,
    thinning: int = ...,
    particles: int = ...,
    svgd_iterations: int = ...,
    svgd_spread: float = ...,
    temper: bool = ...,
    global_feature_points: int = ...,
    global_normal_neighbors: int = ...,
    global_feature_radius: float = ...,
    global_inlier_distance: float = ...,
    global_max_iterations: int = ...,
    global_confidence: float = ...,
    global_hypotheses: int = ...,
    global_distinct_rotation: float = ...,
    global_distinct_translation: float = ...,
    global_refined_hypotheses: int = ...,
    global_fine_distance: float = ...,
    global_ambiguity_ratio: float = ...,
    global_min_score: float = ...,
    global_min_points: int = ...,
) -> RegistrationResult:
    """Registers `source` to `reference` with SGD-ICP, or with a batch ICP method.

    Returns a RegistrationResult whose T_reference_source (4x4, float64, metres) maps source points
    into the reference frame: p_ref = R @ p_src + t.

    Parameters
    ----------
    source : (N, 3) float32 or float64 array, metres
        The cloud that moves. Any memory layout (C, Fortran, strided slices). It is copied once into
        the library's float32 storage (float64 georeferenced coordinates, e.g. UTM, are stored
        from an
        origin near the cloud, exactly: docs/io.md); rows with a NaN or infinite coordinate are
        dropped
        and counted (result.source_non_finite_dropped).
    reference : (M, 3) array like `source`, or ReferenceIndex
        The fixed cloud. A ReferenceIndex is built once and reused by any number of registrations,
        also from several threads at once; an array builds one for this call (result.build_ms),
        with the normals or covariances the cost needs.
    init : (4, 4) array, None or 'global', default None (identity)
        Initial T_reference_source; must be rigid. 'global': no initial guess; a global estimate
        (FPFH features and RANSAC, verified against the reference; docs/global.md), then the SGD
        registration from it. The result's global_* fields name the winning hypothesis, its score
        and the runner-up's; global_reliable False means no reliable global solution (too few
        points, no structure, an ambiguous scene): do not use the transform. SGD methods only.
    settings : Settings, BatchSettings or None, default None
        The base settings: a Settings for the SGD methods (None = Settings()), a BatchSettings for
        the batch methods (None = BatchSettings(), whose cost the method sets).
    method : str, default 'sgd'
        The CLI's --method: 'sgd' (SGD-ICP with the settings' cost, point-to-plane by default,
        point-to-point with Settings.paper()), 'sgd-point' / 'sgd-plane' / 'sgd-gicp' (SGD-ICP on
        point-to-point / point-to-plane / plane-to-plane), 'icp' (batch
        point-to-point, closed-form SVD step), 'icp-plane' (batch point-to-plane) or 'gicp' (batch
        plane-to-plane), both Levenberg-Marquardt. All but 'sgd' set the cost (cost= is then an
        error). An unknown name raises InvalidSettingsError.
    **overrides
        Keyword settings applied on top of `settings`, named like the CLI's options (the library's
        settings table), each with its default and valid range. The common ones come first; the
        others are better kept together in `settings`, which any number of calls can share
        (settings=sgd_icp.Settings(refine_stages=2, trim=0.8)). A distance given as a number is in
        max_distance_unit ('scaled', the default, or 'm'); a Distance keeps its own unit.
        optimizer= also sets learning_rate to that rule's own step unless learning_rate= is given.
        For the batch methods (any other keyword raises TypeError):
        max_distance (Distance.scaled(0.05)), max_iterations (100, [1, 1000000000]),
        damping (1e-06, [0, 100]), translation_tolerance (1e-05, [0, 0.01]),
        rotation_tolerance (1e-05, [0, 0.01]), evaluation_points (2000, [0, 4294967295]),
        cost (CostType.point_to_point), kernel (KernelType.none),
        kernel_scale (Distance.scaled(0.01)), trim (1.0, [0.01, 1]), neighbors (20, [3, 1000]),
        threads (1, [0, 1024]), voxel_size (0.0, [0, 1000000]), downsample_to (0, [0, 4294967295]),
        record_trace (False).
        For the SGD methods:
        The common ones:
          max_distance (Distance.scaled(0.5)), seed (2019, [0, 2^64-1]), threads (1, [0, 1024]),
          voxel_size (0.0, [0, 1000000]), uncertainty (UncertaintyType.none).
        The others, by the part of the run that reads them:
        Step rule:
          optimizer (OptimizerType.adam), learning_rate (0.01, [1e-06, 10000]),
          damping (0.001, [0, 100]);
        Sampling (the mini-batches):
          batch_size (160, [1, 10000000]);
        Registration run:
          max_iterations (4000, [1, 1000000000]), average (True),
          evaluation_points (2000, [0, 4294967295]), cost (CostType.point_to_plane),
          coarse_cost (CostType.point_to_point), record_trace (False);
        Convergence:
          window (20, [8, 100000]), chi2 (12.59, (0, 1000]),
          translation_tolerance (1e-06, [0, 0.01]), rotation_tolerance (1e-06, [0, 0.01]);
        Refinement:
          refine_stages (3, [0, 100]), step_decay (0.5, [0.01, 1]),
          distance_factor (3.0, [1, 1000]), min_distance (Distance.scaled(0.0001));
        Scaling:
          scaling_origin (ScalingOrigin.center);
        Pairs and robust costs:
          kernel (KernelType.none), kernel_scale (Distance.scaled(0.01)), trim (1.0, [0.01, 1]);
        Surfaces (normals, covariances):
          neighbors (20, [3, 1000]);
        Downsampling:
          downsample_to (20000, [0, 4294967295]);
        Uncertainty:
          uncertainty_samples (200, [2, 1000000]), thinning (5, [1, 10000]),
          particles (32, [1, 10000]), svgd_iterations (50, [1, 1000000]),
          svgd_spread (3.0, [0.001, 1000000000]), temper (True).
        With init='global' (an error without it), the global estimate's settings, named like the
        CLI's --global-* options (docs/global.md):
        global_feature_points (3000, [10, 10000000]), global_normal_neighbors (12, [3, 1000]),
        global_feature_radius (5.0, (0, 1000]), global_inlier_distance (1.5, (0, 1000]),
        global_max_iterations (100000, [1, 100000000]), global_confidence (0.999, (0, 1)),
        global_hypotheses (8, [1, 1000]), global_distinct_rotation (10.0, [0, 180]),
        global_distinct_translation (3.0, [0, 1000]), global_refined_hypotheses (3, [1, 1000]),
        global_fine_distance (0.5, (0, 1000]), global_ambiguity_ratio (0.9, (0, 1]),
        global_min_score (0.05, [0, 1]), global_min_points (30, [3, 10000000]).
        See docs/python-settings.md for the settings each one sets.

    The GIL is released during the registration (and the KD-tree build), so registrations in
    several Python threads run in parallel.

    Raises
    ------
    InvalidInputError (ValueError)
        A wrong shape or dtype, no finite points, fewer source points than batch_size, a non-rigid
        init, a ReferenceIndex without the normals or covariances of a batch method's cost (build
        it with ReferenceIndex(points, cost=...); the SGD methods estimate what they use).
    InvalidSettingsError (ValueError)
        An invalid setting or method name, or a global_* keyword without init='global'.
    TypeError
        An unknown keyword, a keyword of the other solver, or a value of the wrong type.
    """


# ---- preprocessing


def voxel_downsample(points: _Points, voxel_size_m: float) -> npt.NDArray[np.float32]:
    """One point per occupied cubic voxel: the centroid of the points in it.

    Parameters
    ----------
    points : (N, 3) float32 or float64 array, metres
        Any memory layout; rows with a NaN or infinite coordinate are dropped first. May be empty.
    voxel_size_m : float
        Side of the voxels, metres, positive. Voxel (i, j, l) holds the points with
        floor(x / voxel_size_m) = i, etc.

    Returns
    -------
    (M, 3) float32 array, metres, M <= N: in the order of each voxel's first point in the input
    (deterministic). The GIL is released while it runs.

    Raises
    ------
    InvalidSettingsError (ValueError)
        voxel_size_m not positive and finite, or so small that voxel indices overflow.
    InvalidInputError (ValueError)
        Not an (N, 3) float32/float64 array.
    """


def random_downsample(points: _Points, count: int, seed: int = 2019) -> npt.NDArray[np.float32]:
    """`count` distinct points chosen uniformly at random without replacement.

    Parameters
    ----------
    points : (N, 3) float32 or float64 array, metres
        Any memory layout; rows with a NaN or infinite coordinate are dropped first. May be empty.
    count : int
        Points to keep, >= 0; count >= N returns all the (finite) points.
    seed : int, default 2019
        Seed of the draw (std::mt19937_64): the same points, count and seed give the same result on
        any platform.

    Returns
    -------
    (min(count, N), 3) float32 array, metres, in input order. The GIL is released while it runs.
    """


def estimate_normals(
    points: _Points,
    k: int = 20,
    num_threads: int = 0,
    *,
    viewpoint: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """Unit normals from the k nearest neighbours of every point.

    The normal is the eigenvector of the smallest eigenvalue of the neighbourhood's covariance
    (PCA),
    flipped to face `viewpoint`. Degenerate neighbourhoods (all points identical or collinear) have
    no surface: their normal is (0, 0, 0). The results are the same for any thread count.

    Parameters
    ----------
    points : (N, 3) float32 or float64 array, metres
        Any memory layout; every row must be finite (one normal is returned per row).
    k : int, default 20
        Neighbours per point, the point itself included, in [3, 1000].
    num_threads : int, default 0
        Worker threads, 0 = all cores, at most 1024. The GIL is released while it runs.
    viewpoint : (3,) array or None, default None (the origin)
        Normals are flipped to face this point (metres): n . (viewpoint - p) >= 0.

    Returns
    -------
    (N, 3) float32 array of unit normals (or zero rows), one per input row.

    Raises
    ------
    InvalidInputError (ValueError)
        Not an (N, 3) float32/float64 array, no rows, or a non-finite row.
    InvalidSettingsError (ValueError)
        k or num_threads out of range.
    """


def estimate_covariances(
    points: _Points,
    k: int = 20,
    num_threads: int = 0,
    *,
    regularize: bool = True,
    epsilon: float = 1e-3,
) -> npt.NDArray[np.float32]:
    """Local covariances from the k nearest neighbours of every point.

    Raw covariance: (1/n) sum (q - mean)(q - mean)^T over the n = min(k, N) neighbours, in m^2.
    With regularize=True (the default, as GICP uses them) each is replaced by the unitless plane
    model V diag(epsilon, 1, 1) V^T, V its eigenvectors (smallest first); degenerate neighbourhoods
    then get the identity. The results are the same for any thread count.

    Parameters
    ----------
    points : (N, 3) float32 or float64 array, metres
        Any memory layout; every row must be finite (one covariance is returned per row).
    k : int, default 20
        Neighbours per point, the point itself included, in [3, 1000].
    num_threads : int, default 0
        Worker threads, 0 = all cores, at most 1024. The GIL is released while it runs.
    regularize : bool, default True
        Return the GICP plane model (unitless) instead of the raw covariance (m^2).
    epsilon : float, default 1e-3
        Variance along the normal in the plane model, relative to 1 in the plane, in (0, 1].

    Returns
    -------
    (N, 3, 3) float32 array of symmetric matrices, one per input row.

    Raises
    ------
    InvalidInputError (ValueError)
        Not an (N, 3) float32/float64 array, no rows, or a non-finite row.
    InvalidSettingsError (ValueError)
        k, num_threads or epsilon out of range.
    """


# ---- files


class ReadResult:
    """A point cloud read from a file, with its counts."""

    @property
    def points(self) -> npt.NDArray[np.float32] | npt.NDArray[np.float64]:
        """(N, 3) float32 array of the finite points, in file order, metres (float64 for
        georeferenced coordinates, which float32 cannot hold: docs/io.md).
        """
    @property
    def times(self) -> npt.NDArray[np.float32] | None:
        """(N,) float32 array of each point's time, seconds from the earliest, when the file has a
        per-point time field (docs/io.md, Per-point times), else None: give it to
        Odometry.register_frame(points, times=...).
        """
    @property
    def points_in_file(self) -> int:
        """Points the file declares or contains (= N + non_finite_dropped)."""
    @property
    def non_finite_dropped(self) -> int:
        """Points dropped for a NaN or infinite coordinate."""
    @property
    def format(self) -> str:
        """The format read: 'pcd', 'ply', 'kitti_bin', 'xyz', 'vtk' or 'f32'."""


def read_point_cloud(path: _Path, format: str = "auto") -> ReadResult:
    """Reads the x y z of every point of a file (PCD, PLY, KITTI .bin, .xyz/.txt/.csv, ASCII VTK,
    .f32; docs/io.md) into a ReadResult. format: 'auto' (from the extension, the default), 'pcd',
    'ply', 'kitti_bin', 'xyz', 'vtk' or 'f32'. Points with a NaN or infinite coordinate are
    dropped and counted. Raises IoError (OSError) or FormatError (ValueError).
    """


def read_points(
    path: _Path, format: str = "auto"
) -> npt.NDArray[np.float32] | npt.NDArray[np.float64]:
    """Reads a point-cloud file into an (N, 3) float32 array (metres) of its finite points (float64
    for georeferenced coordinates, docs/io.md); see read_point_cloud for the formats, the counts
    and the errors.
    """


def read_transform(path: _Path) -> npt.NDArray[np.float64]:
    """Reads a transform file as the CLI's --init does (12 numbers, a 3x4 [R | t], or 16, a 4x4,
    row-major; '#' comment lines; projected onto the nearest rotation) into a (4, 4) float64
    array. Raises IoError (OSError) or FormatError (ValueError).
    """


def read_pairs(
    path: _Path,
) -> list[tuple[str, str, npt.NDArray[np.float64], int]]:
    """Reads a pairs file (one SOURCE REFERENCE and ground-truth T_reference_source per line, the
    format of `sgdicp bench`: shared/data/PAIRS.md) into a list of (source, reference, T_gt,
    line) tuples: the paths resolved against the file's folder, T_gt a (4, 4) float64 array, line
    the line number in the file. Raises IoError (OSError) or FormatError (ValueError) naming the
    file and line.
    """


def write_points(
    path: _Path, points: _Points, format: str = "auto", encoding: str = "binary"
) -> None:
    """Writes an (N, 3) float32/float64 array as PLY, PCD or XYZ (float32 values; georeferenced
    float64 coordinates as float64), chosen from the extension unless format ('ply', 'pcd',
    'xyz') is given. encoding: 'binary' (default) or 'ascii' (XYZ is always text). Reading the
    file back gives the same values. Raises IoError (OSError) or FormatError (ValueError).
    """


# ---- depth images


_Intrinsics = Union[tuple[float, float, float, float], npt.ArrayLike, _Path]
"""(fx, fy, cx, cy) in pixels, a 3x3 camera matrix, or the path of a 3x3 K file."""


def read_depth_image(
    path: _Path,
    intrinsics: _Intrinsics,
    depth_scale: float = 0.0,
    max_depth: float = 10.0,
    min_depth: float = 0.0,
    pixel_stride: int = 1,
    border: int = 0,
) -> npt.NDArray[np.float32]:
    """Reads a 16-bit greyscale PNG depth image and back-projects its valid pixels into an (N, 3)
    float32 array, metres, in the camera frame (x right, y down, z forward), row by row
    (docs/depth.md). intrinsics: (fx, fy, cx, cy) in pixels, a 3x3 camera matrix, or the path of
    a 3x3 K file (the 7-Scenes camera-intrinsics.txt). depth_scale: stored units per metre, 0 =
    1000 (millimetres; TUM RGB-D: 5000). Pixels of depth 0, or outside [min_depth, max_depth]
    metres, are dropped; pixel_stride takes every n-th pixel in x and y; border drops a band of
    that many pixels along each edge (a Kinect v1's depth is off by up to ~1 cm toward its left
    and right edges). Raises IoError (OSError), FormatError (not a 16-bit greyscale PNG,
    truncated, too many pixels) or InvalidSettingsError (ValueError).
    """


def depth_to_points(
    depth: npt.ArrayLike,
    intrinsics: _Intrinsics,
    depth_scale: float = 0.0,
    max_depth: float = 10.0,
    min_depth: float = 0.0,
    pixel_stride: int = 1,
    border: int = 0,
) -> npt.NDArray[np.float32]:
    """Back-projects a depth image held in memory, as read_depth_image: a 2-D array (rows, columns)
    of uint16 stored units (depth_scale per metre) or of float32/float64 metres (depth_scale
    unused; NaN and infinite depths are dropped too). Returns (N, 3) float32, metres, camera
    frame (x right, y down, z forward). Raises InvalidInputError for another dtype or shape,
    InvalidSettingsError for bad intrinsics or settings.
    """


# ---- metrics


def translation_error(T_est: _Transform, T_gt: _Transform) -> float:
    """|t_est - t_gt| of two (4, 4) transforms, in their unit (metres)."""


def rotation_error_geodesic(T_est: _Transform, T_gt: _Transform) -> float:
    """Angle of the relative rotation R_est^T R_gt of two (4, 4) transforms, radians in [0, pi]."""


def rotation_error_euler_sum(T_est: _Transform, T_gt: _Transform) -> float:
    """The paper's rotation error: |d roll| + |d pitch| + |d yaw| of two (4, 4) transforms, each
    wrapped to (-pi, pi], radians.
    """


class FrameReport:
    """What happened to one frame of an Odometry."""

    @property
    def index(self) -> int:
        """Frame number, from 0."""
    @property
    def T_first_frame(self) -> npt.NDArray[np.float64]:
        """(4, 4) float64 pose of the frame in the first frame's coordinates."""
    @property
    def failed(self) -> bool:
        """True if the frame is lost: no start registered it, the pose is the motion model's
        prediction (see message), and neither the map nor the motion model took it in.
        """
    @property
    def recovered(self) -> bool:
        """True if a retry registered the frame after the registration from the prediction was
        rejected (message says why; start says which retry).
        """
    @property
    def start(self) -> str:
        """Where the accepted registration started: prediction, last pose, wide basin or global."""
    @property
    def overlap(self) -> float:
        """Fraction of the registered frame's points with a map point within one map voxel (a frame
        below half the recent frames' is rejected); 0 when not registered.
        """
    @property
    def doubtful(self) -> bool:
        """Registered, but the pose may be off (message says why after 'doubtful: '): the scene
        leaves some motion unconstrained while the prediction was uncertain, or no start
        overlapped the map like the last frames.
        """
    @property
    def constraint_ratio(self) -> float:
        """The registration's smallest over largest eigenvalue of its point-to-plane information
        (RegistrationResult.constraint_ratio); 0 when not registered.
        """
    @property
    def converged(self) -> bool:
        """True if the registration's convergence test passed."""
    @property
    def message(self) -> str:
        """Why the frame failed, or the registration's stop message."""
    @property
    def iterations(self) -> int:
        """Iterations of the registration."""
    @property
    def source_points(self) -> int:
        """Frame points registered (after cropping and thinning)."""
    @property
    def map_points(self) -> int:
        """Map points registered to."""
    @property
    def inlier_ratio(self) -> float:
        """Inlier ratio of the registration."""
    @property
    def inlier_rmse_m(self) -> float:
        """Inlier RMSE of the registration, metres."""
    @property
    def threshold_m(self) -> float:
        """d_max given to the registration (3 sigma of the adaptive threshold), metres; 0 when
        max_distance= fixes it.
        """
    @property
    def index_build_ms(self) -> float:
        """KD-tree build over the map (plus normals or covariances), milliseconds."""
    @property
    def time_ms(self) -> float:
        """The whole frame (thinning, index, registration, map update), milliseconds."""
    @property
    def covariance(self) -> npt.NDArray[np.float64]:
        """(6, 6) float64 covariance of the frame's pose relative to the map it was registered
        against (uncertainty='laplace', 'sgld' or 'svgd'): the registration's covariance_se3,
        translation first, xi in the frame's own tangent space (T_first_frame = T_hat @ Exp(xi)),
        metres and radians; the map's own error is not in it. The first frame: zeros; a repeated
        frame: the previous frame's; a frame without one (lost, no point, or no uncertainty
        asked): NaN.
        """


class Odometry:
    """Scan-to-map odometry: frames (points in their sensor frame) registered one at a time to a
    local voxel map, from the last motion's share that carried over between frames, with an
    adaptive correspondence threshold (docs/odometry.md).
    """

    def __init__(
        self,
        method: str = "sgd",
        deskew: str = "auto",
        *,
        max_range: float = ...,
        voxel_size: float = ...,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        uncertainty: _UncertaintyName = ...,
        min_range: float = ...,
        max_points_per_voxel: int = ...,
        initial_threshold: float = ...,
        min_motion: float = ...,
        max_translation_per_frame: float = ...,
        max_rotation_per_frame: float = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
    ) -> None:
        """method: the registration step, a --method of the CLI (sgd, sgd-point, sgd-plane,
        sgd-gicp, icp, icp-plane or gicp). settings: the registration's base settings, as
        register()'s (a Settings, or a BatchSettings for a batch method; None = the defaults).
        Keywords: the odometry settings of `sgdicp odometry` (max_range (100 m), min_range (0 m),
        voxel_size (0 m), max_points_per_voxel (20), initial_threshold (0 m), min_motion (0 m),
        max_translation_per_frame (0 m), max_rotation_per_frame (180 deg); 0 = derived from the
        data, docs/odometry.md), deskew= ('auto', 'none', 'azimuth') and the keywords of
        register() for the method; most runs set at most voxel_size=, max_range=, threads= and
        uncertainty=. max_distance= fixes d_max and turns the adaptive threshold off. Raises
        TypeError for an unknown keyword, InvalidSettingsError for an invalid value.
        """
    def register_frame(
        self, points: _Points, times: npt.ArrayLike | None = None
    ) -> npt.NDArray[np.float64]:
        """Registers the next frame, an (N, 3) float32/float64 array in its sensor frame (metres),
        and returns its (4, 4) pose in the first frame's coordinates (the first frame: the
        identity). times: None, or each point's time (N,), seconds, any origin: the frame is then
        deskewed (deskew='auto', docs/deskewing.md). A frame that fails (see last_report) gets
        the predicted pose.
        """
    def skip_frame(self, message: str) -> npt.NDArray[np.float64]:
        """Records a frame that could not be read: it gets the predicted pose and a failed report
        with `message`.
        """
    @property
    def poses(self) -> npt.NDArray[np.float64]:
        """(K, 4, 4) float64 poses of the frames so far, in the first frame's coordinates."""
    @property
    def reports(self) -> list[FrameReport]:
        """A FrameReport per frame so far."""
    @property
    def last_report(self) -> FrameReport | None:
        """The FrameReport of the last frame, or None before the first."""
    @property
    def voxel_size(self) -> float:
        """The map's voxel size in use, metres (0 before the first frame when derived)."""
    @property
    def map_points(self) -> int:
        """Points in the local map."""
    def map_cloud(self, voxel_size: float = 0.0) -> npt.NDArray[np.float32]:
        """The local map's points (what the next frame is registered to: the voxels within max_range
        of the last pose), an (N, 3) float32 array in the first frame's coordinates (metres),
        thinned to one centroid per voxel of voxel_size metres when above 0. The whole map:
        whole_map().
        """
    def keep_whole_map(self, voxel_size: float = 0.0) -> None:
        """From the next frame on, keeps the whole map: every registered frame's points in the first
        frame's coordinates, one centroid per voxel of voxel_size metres (0 = the odometry's
        voxel, following it when it grows), as `sgdicp odometry --map-out --map-voxel` writes it.
        Lost frames do not enter it; its memory grows with the space covered, not with the
        frames.
        """
    def whole_map(self) -> npt.NDArray[np.float32]:
        """The whole map kept since keep_whole_map(): an (N, 3) float32 array in the first frame's
        coordinates (metres); empty before keep_whole_map() or any registered frame.
        """
    @property
    def lost_frames(self) -> int:
        """Frames lost so far (no start registered them, or unreadable)."""
    @property
    def doubtful_frames(self) -> int:
        """Frames registered but doubtful so far (FrameReport.doubtful)."""
    @property
    def recovered_frames(self) -> int:
        """Frames registered by a retry so far."""
    @property
    def method(self) -> str:
        """The registration method's name."""
    def __len__(self) -> int: ...

class Localizer(Odometry):
    """Localization in a map made before: an Odometry whose map is fixed (never extended), the first
    frame placed by the global registration (or from init), every later one from the motion
    model's prediction; a frame the map does not hold is lost, not placed. Poses are in the map's
    coordinates (docs/localization.md).
    """

    def __init__(
        self,
        map: _Points,
        init: _Transform | None = None,
        method: str = "sgd",
        deskew: str = "auto",
        *,
        max_range: float = ...,
        voxel_size: float = ...,
        max_distance: _DistanceValue = ...,
        seed: int = ...,
        threads: int = ...,
        uncertainty: _UncertaintyName = ...,
        min_range: float = ...,
        max_points_per_voxel: int = ...,
        initial_threshold: float = ...,
        min_motion: float = ...,
        max_translation_per_frame: float = ...,
        max_rotation_per_frame: float = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        batch_size: int = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        evaluation_points: int = ...,
        cost: _CostName = ...,
        coarse_cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        record_trace: bool = ...,
        uncertainty_samples: int = ...,
        thinning: int = ...,
        particles: int = ...,
        svgd_iterations: int = ...,
        svgd_spread: float = ...,
        temper: bool = ...,
    ) -> None:
        """map: (N, 3) float32/float64 array of the map's points, metres. init: the first frame's
        (4, 4) pose in the map, or None (the global registration places it). method and the
        keywords: as Odometry's. Raises InvalidInputError for a map without a finite point or
        georeferenced (coordinates beyond 16 km, not supported yet).
        """
    @property
    def map_build_ms(self) -> float:
        """The time the map's voxels and surfaces took to build (at the first frame), ms; 0 before.
        """
