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
_Points = npt.ArrayLike
"""An (N, 3) float32 or float64 array of points in metres, any memory layout."""
_Transform = npt.ArrayLike
"""A (4, 4) rigid transform, metres."""
_OptimizerName = Union["OptimizerType", str]
_OriginName = Union["ScalingOrigin", str]
_CostName = Union["CostType", str]
_KernelName = Union["KernelType", str]
_UnitName = Union["DistanceUnit", str]
_DistanceValue = Union[float, "Distance"]
_MethodName = Literal["sgd", "sgd-plane", "sgd-gicp", "icp", "icp-plane", "gicp"]

# ---- errors


class Error(Exception):
    """Base class of every error the sgd_icp library raises."""


class InvalidInputError(Error, ValueError):
    """Input the method cannot work with: a wrong array shape or dtype, an empty or all-NaN cloud,
    fewer source points than a mini-batch, a non-rigid initial transform."""


class InvalidSettingsError(Error, ValueError):
    """A setting out of range or contradicting another."""


class FormatError(Error, ValueError):
    """A file whose content is not valid for its format; the message names the file and the line
    or byte where it broke."""


class IoError(Error, OSError):
    """A file that cannot be opened, read or written; the message names the path and the reason."""


# ---- settings


class DistanceUnit(enum.Enum):
    """Unit of a Distance."""

    metres = 0
    """Metres."""
    scaled = 1
    """Fractions of the largest side of the joint bounding box of both clouds."""


class OptimizerType(enum.Enum):
    """Step rule of the paper's eq. 3."""

    sgd = 0
    """Fixed step (the paper's vanilla SGD, alpha = 2)."""
    momentum = 1
    """Heavy-ball momentum."""
    rmsprop = 2
    """RMSProp."""
    adam = 3
    """Adam (the paper's Adam-SGD; the default)."""
    gauss_newton = 4
    """Step pre-conditioned by the averaged mini-batch Gauss-Newton matrix."""


class ScalingOrigin(enum.Enum):
    """Origin of the scaled space, which is also the pivot of the rotation."""

    lower_corner = 0
    """The paper: the lower corner of the joint box, points in [0, 1]."""
    center = 1
    """The centre of the joint box, points in [-0.5, 0.5] (the default)."""


class CostType(enum.Enum):
    """Cost of a pair (source point moved to q, reference point r)."""

    point_to_point = 0
    """|q - r|^2, the paper's (Besl-McKay); the default."""
    point_to_plane = 1
    """(n . (q - r))^2 with the reference normal n (Chen-Medioni)."""
    plane_to_plane = 2
    """e^T (C_r + R C_s R^T)^-1 e with the plane covariances (GICP, Segal et al.)."""


class KernelType(enum.Enum):
    """Robust kernel on each pair's squared residual."""

    none = 0
    """No kernel (least squares); the default."""
    huber = 1
    """Huber."""
    cauchy = 2
    """Cauchy."""
    geman_mcclure = 3
    """Geman-McClure."""
    welsch = 4
    """Welsch."""


class Distance:
    """A length with its unit: metres, or scaled units (1 = the largest side of the joint bounding
    box of both clouds). Make one with Distance.metres(v) or Distance.scaled(v)."""

    value: float
    """The length, in `unit`."""
    unit: DistanceUnit
    """DistanceUnit.metres or DistanceUnit.scaled (assign 'm' or 'scaled' too)."""

    def __init__(self, value: float, unit: _UnitName = "scaled") -> None:
        """A distance of `value` in `unit` ('m', 'scaled' or a DistanceUnit; default 'scaled')."""

    @staticmethod
    def metres(value: float) -> Distance:
        """A distance in metres."""

    @staticmethod
    def scaled(value: float) -> Distance:
        """A distance in scaled units (fraction of the largest side of the joint box)."""

    def to_scaled(self, metres_per_unit: float) -> float:
        """The value in scaled units, given the metres per scaled unit (RegistrationResult.scale_m)."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> Distance: ...
    def __deepcopy__(self, memo: Any) -> Distance: ...


class OptimizerSettings:
    """Step rule of eq. 3 and its parameters (Settings.optimizer). A new OptimizerSettings() has
    the C++ struct's defaults (fixed step, learning rate 2); Settings() uses Adam with 0.01."""

    type: OptimizerType
    """Step rule (assign a name too: 'sgd', 'momentum', 'rmsprop', 'adam', 'gauss-newton').
    Settings() default: OptimizerType.adam."""
    learning_rate: float
    """alpha of eq. 3, scaled units per unit gradient. Settings() default 0.01 (Adam); the paper's
    fixed step uses 2; Gauss-Newton: fraction of a Newton step, 1."""
    momentum: float
    """Momentum: velocity decay, in [0, 1). Default 0.9."""
    beta1: float
    """Adam: decay of the mean of gradients, in [0, 1). Default 0.9."""
    beta2: float
    """Adam: decay of the mean of squared gradients, in [0, 1). Default 0.999."""
    rms_decay: float
    """RMSProp: decay of the mean of squared gradients, in [0, 1). Default 0.9."""
    epsilon: float
    """Adam/RMSProp: added to the root mean square, scaled units. Default 1e-8."""
    hessian_decay: float
    """Gauss-Newton: decay of the running average of the mini-batch Gauss-Newton matrices, in
    [0, 1). Default 0.9."""
    damping: float
    """Gauss-Newton: Levenberg damping relative to the mean diagonal. Default 1e-3."""

    def __init__(self) -> None: ...
    def validate(self) -> None:
        """Raises InvalidSettingsError naming the first invalid value."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> OptimizerSettings: ...
    def __deepcopy__(self, memo: Any) -> OptimizerSettings: ...


class ConvergenceSettings:
    """When a stage is stationary: Hotelling's T^2 test on the window's mini-batch gradients and a
    path-efficiency guard, or an absolute tolerance on every step (Settings.convergence)."""

    window: int
    """Iterations per test window, >= 8; also the length of the final iterate average. Default 20."""
    chi2: float
    """Critical chi-square value (6 degrees of freedom) of the test; larger stops earlier.
    Default 12.59 (95 %)."""
    max_path_efficiency: float
    """Largest |sum of steps| / sum of |steps| of a stationary window, in (0, 1]. Default 0.5."""
    translation_tolerance: float
    """A window whose steps all move the translation less than this (scaled units) ...
    Default 1e-6."""
    rotation_tolerance: float
    """... and the angles less than this (sum of |d roll|, |d pitch|, |d yaw|, rad) is stationary.
    Default 1e-6."""

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> ConvergenceSettings: ...
    def __deepcopy__(self, memo: Any) -> ConvergenceSettings: ...


class RefinementSettings:
    """Refinement stages after the paper's coarse phase: each shrinks d_max to the data and decays
    the step (Settings.refinement)."""

    stages: int
    """Refinement stages after the coarse phase (0 = the paper's single phase). Default 3."""
    step_decay: float
    """Step-size multiplier per stage, in (0, 1]. Default 0.5."""
    distance_factor: float
    """New d_max = factor x median pair distance of the stage. Default 3."""
    min_distance: Distance
    """Floor of d_max. Default Distance.scaled(1e-4)."""

    def __init__(self) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> RefinementSettings: ...
    def __deepcopy__(self, memo: Any) -> RefinementSettings: ...


class NeighborhoodSettings:
    """k-nearest neighbourhoods for the normals and covariances of the plane costs
    (Settings.neighborhood)."""

    k: int
    """Neighbours per point, the point included, in [3, 1000]. Default 20."""
    num_threads: int
    """Worker threads of the estimation; 0 = all cores (the same results for any count).
    Default 0."""
    regularize: bool
    """Replace each covariance by the GICP plane model (unitless). Default True."""
    epsilon: float
    """Variance along the normal in the plane model, relative to 1 in the plane, in (0, 1].
    Default 1e-3."""
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
    """m of the paper: source points per mini-batch. Default 160."""
    max_correspondence_distance: Distance
    """d_max: pairs farther apart are rejected. Default Distance.scaled(0.5)."""
    optimizer: OptimizerSettings
    """Step rule and its parameters. Default Adam with learning rate 0.01."""
    convergence: ConvergenceSettings
    """Stationarity test."""
    refinement: RefinementSettings
    """Refinement stages."""
    cost: CostType
    """Cost of a pair (assign a name too: 'point-to-point', 'point-to-plane', 'plane-to-plane').
    The plane costs need reference normals / covariances. Default CostType.point_to_point."""
    kernel: KernelType
    """Robust kernel on each pair's residual (assign a name too: 'none', 'huber', 'cauchy',
    'geman-mcclure', 'welsch'). Default KernelType.none."""
    kernel_scale: Distance
    """Residual size where the kernel starts to down-weight. Default Distance.scaled(0.01)."""
    trim_ratio: float
    """Keep only this fraction of each mini-batch's pairs, the closest ones (trimmed ICP, for
    partial overlap), in (0, 1]. Default 1."""
    neighborhood: NeighborhoodSettings
    """Neighbourhoods for the normals and covariances of the plane costs."""
    scaling_origin: ScalingOrigin
    """Origin of the scaled space and pivot of the rotation (assign 'center' or 'lower_corner'
    too). Default ScalingOrigin.center."""
    max_iterations: int
    """Iteration (mini-batch) limit; reaching it means not converged. Default 4000."""
    seed: int
    """Seed of the mini-batch sampler; same inputs and seed give the same result. Default 2019."""
    average_iterates: bool
    """Return the mean of the final stage's iterates instead of the last one. Default True."""
    evaluation_points: int
    """Source points (spread evenly) for the final inlier statistics; 0 = all. Default 2000."""
    record_trace: bool
    """Fill RegistrationResult.trace. Default False."""
    check_degeneracy: bool
    """Check the final alignment for degenerate geometry (a plane, a corridor) and report it in
    RegistrationResult.constraint_ratio / degenerate. Default True."""

    def __init__(
        self,
        *,
        batch_size: int = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        seed: int = ...,
        momentum: float = ...,
        beta1: float = ...,
        beta2: float = ...,
        rms_decay: float = ...,
        epsilon: float = ...,
        hessian_decay: float = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        path_efficiency: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        check_degeneracy: bool = ...,
        evaluation_points: int = ...,
        record_trace: bool = ...,
    ) -> None:
        """The default settings with the flat keyword overrides applied (see register())."""

    @staticmethod
    def paper(
        optimizer: _OptimizerName = "sgd",
        *,
        batch_size: int = ...,
        learning_rate: float = ...,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        seed: int = ...,
        momentum: float = ...,
        beta1: float = ...,
        beta2: float = ...,
        rms_decay: float = ...,
        epsilon: float = ...,
        hessian_decay: float = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        path_efficiency: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        check_degeneracy: bool = ...,
        evaluation_points: int = ...,
        record_trace: bool = ...,
    ) -> Settings:
        """The paper's settings: m = 160, d_max = 0.5 scaled, fixed step alpha = 2 ('sgd') or Adam
        0.01 ('adam'), no refinement, the last iterate, the lower-corner scaling origin; then the
        keyword overrides."""

    def replace(
        self,
        *,
        batch_size: int = ...,
        optimizer: _OptimizerName = ...,
        learning_rate: float = ...,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        seed: int = ...,
        momentum: float = ...,
        beta1: float = ...,
        beta2: float = ...,
        rms_decay: float = ...,
        epsilon: float = ...,
        hessian_decay: float = ...,
        damping: float = ...,
        window: int = ...,
        chi2: float = ...,
        path_efficiency: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        refine_stages: int = ...,
        step_decay: float = ...,
        distance_factor: float = ...,
        min_distance: _DistanceValue = ...,
        average: bool = ...,
        scaling_origin: _OriginName = ...,
        cost: _CostName = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        check_degeneracy: bool = ...,
        evaluation_points: int = ...,
        record_trace: bool = ...,
    ) -> Settings:
        """A copy with the flat keyword overrides of register() applied."""

    def validate(self) -> None:
        """Raises InvalidSettingsError naming the first invalid setting."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> Settings: ...
    def __deepcopy__(self, memo: Any) -> Settings: ...


class BatchSettings:
    """Settings of the batch methods (register(method='icp' | 'icp-plane' | 'gicp')): the C++
    sgdicp::BatchSettings, same names and defaults. Every iteration pairs all source points with
    their nearest reference point within d_max, then takes the closed-form SVD step
    (point-to-point) or one damped Gauss-Newton step (the plane costs).

    BatchSettings(**overrides) is the default (point-to-point) with the batch keyword overrides of
    register() applied; BatchSettings.icp(), .icp_plane() and .gicp() set the cost.
    """

    cost: CostType
    """Cost of a pair (assign a name too). register(method=...) replaces it with the method's
    cost. Default CostType.point_to_point."""
    max_correspondence_distance: Distance
    """d_max: pairs farther apart are rejected (scaled: fraction of the largest side of the joint
    bounding box). Default Distance.scaled(0.05)."""
    kernel: KernelType
    """Robust kernel on each pair's residual (assign a name too). Default KernelType.none."""
    kernel_scale: Distance
    """Residual size where the kernel starts to down-weight. Default Distance.scaled(0.01)."""
    trim_ratio: float
    """Keep only this fraction of each iteration's pairs, the closest ones (trimmed ICP), in
    (0, 1]. Default 1."""
    max_iterations: int
    """Iteration limit (passes over the source); reaching it means not converged. Default 100."""
    translation_tolerance: float
    """Converged when an iteration moves the translation less than this (scaled units) ...
    Default 1e-5."""
    rotation_tolerance: float
    """... and the rotation less than this (rotation angle, rad). Default 1e-5."""
    initial_damping: float
    """Initial Levenberg-Marquardt damping, relative to the mean diagonal of J^T J; 0 = plain
    Gauss-Newton; unused by point-to-point. Default 1e-6."""
    neighborhood: NeighborhoodSettings
    """Neighbourhoods for the normals and covariances of the plane costs."""
    evaluation_points: int
    """Source points (spread evenly) for the final inlier statistics; 0 = all. Default 2000."""
    check_degeneracy: bool
    """Check the final alignment for degenerate geometry and report it in
    RegistrationResult.constraint_ratio / degenerate. Default True."""
    record_trace: bool
    """Fill RegistrationResult.trace: one entry per iteration (pose, step size 1, d_max, pairs,
    mean squared pair distance). Default False."""

    def __init__(
        self,
        *,
        max_distance: _DistanceValue = ...,
        max_distance_unit: _UnitName = ...,
        max_iterations: int = ...,
        kernel: _KernelName = ...,
        kernel_scale: _DistanceValue = ...,
        trim: float = ...,
        neighbors: int = ...,
        damping: float = ...,
        translation_tolerance: float = ...,
        rotation_tolerance: float = ...,
        evaluation_points: int = ...,
        check_degeneracy: bool = ...,
        record_trace: bool = ...,
        cost: _CostName = ...,
    ) -> None:
        """The default settings (point-to-point ICP) with the batch keyword overrides applied
        (see register(); damping sets initial_damping, trim trim_ratio, neighbors
        neighborhood.k)."""

    @staticmethod
    def icp(**overrides: Any) -> BatchSettings:
        """Point-to-point ICP (Besl-McKay; closed-form SVD step), then the keyword overrides."""

    @staticmethod
    def icp_plane(**overrides: Any) -> BatchSettings:
        """Point-to-plane ICP (Chen-Medioni; Levenberg-Marquardt step), then the keyword
        overrides."""

    @staticmethod
    def gicp(**overrides: Any) -> BatchSettings:
        """Plane-to-plane GICP (Segal et al.; Levenberg-Marquardt step), then the keyword
        overrides."""

    def replace(self, **overrides: Any) -> BatchSettings:
        """A copy with the batch keyword overrides applied."""

    def validate(self) -> None:
        """Raises InvalidSettingsError naming the first invalid setting."""

    def __eq__(self, other: object) -> bool: ...
    def __copy__(self) -> BatchSettings: ...
    def __deepcopy__(self, memo: Any) -> BatchSettings: ...


# ---- registration


class ReferenceIndex:
    """A KD-tree over a reference cloud, built once and reused by any number of registrations,
    also from several threads at once (queries are read-only)."""

    def __init__(
        self,
        points: _Points,
        *,
        leaf_size: int = 10,
        cost: _CostName = "point-to-point",
        neighborhood: NeighborhoodSettings | None = None,
    ) -> None:
        """Builds the tree over an (N, 3) float32/float64 array of points in metres (copied once
        into float32 storage; rows with a NaN or infinite coordinate are dropped and counted).

        Args:
            points: (N, 3) float32/float64 array, metres.
            leaf_size: points per KD-tree leaf. Default 10.
            cost: the cost the index will serve: 'point-to-plane' estimates the reference
                normals, 'plane-to-plane' the covariances (and normals). Default 'point-to-point'.
            neighborhood: how normals and covariances are estimated. Default None =
                NeighborhoodSettings().

        The GIL is released during the build; the index never changes afterwards: a
        registration whose method needs normals ('sgd-plane', 'icp-plane', cost='point-to-plane')
        or covariances ('sgd-gicp', 'gicp', cost='plane-to-plane') that the index lacks raises
        InvalidInputError instead of adding them."""

    def __len__(self) -> int: ...
    @property
    def points(self) -> npt.NDArray[np.float32]:
        """The indexed points: a read-only (N, 3) float32 view (no copy)."""
    @property
    def non_finite_dropped(self) -> int:
        """Rows of the input dropped for a NaN or infinite coordinate."""
    @property
    def build_ms(self) -> float:
        """Wall time of the KD-tree build (and of the normals or covariances), milliseconds."""
    @property
    def has_normals(self) -> bool:
        """Whether the reference has normals (cost 'point-to-plane' or 'plane-to-plane')."""
    @property
    def has_covariances(self) -> bool:
        """Whether the reference has covariances (cost 'plane-to-plane')."""
    @property
    def bounding_box(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(min, max) corners of the axis-aligned bounding box, two (3,) float64 arrays, metres."""


class Trace:
    """Per-iteration record of a registration (record_trace=True), one element per iteration."""

    @property
    def iteration(self) -> npt.NDArray[np.int64]:
        """(K,) iteration number."""
    @property
    def points_processed(self) -> npt.NDArray[np.int64]:
        """(K,) source points drawn so far."""
    @property
    def T_reference_source(self) -> npt.NDArray[np.float64]:
        """(K, 4, 4) metric pose after each iteration."""
    @property
    def step_size(self) -> npt.NDArray[np.float64]:
        """(K,) effective learning rate of each iteration (scaled units)."""
    @property
    def max_distance_m(self) -> npt.NDArray[np.float64]:
        """(K,) d_max used, metres."""
    @property
    def inliers(self) -> npt.NDArray[np.int64]:
        """(K,) pairs kept in each mini-batch."""
    @property
    def cost(self) -> npt.NDArray[np.float64]:
        """(K,) mini-batch cost F, scaled units^2."""
    def __len__(self) -> int: ...


class RegistrationResult:
    """What register() returns: every field of the C++ RegistrationResult, plus the point counts
    and the KD-tree build time."""

    @property
    def T_reference_source(self) -> npt.NDArray[np.float64]:
        """(4, 4), metres: maps source points into the reference frame, p_ref = R @ p_src + t."""
    @property
    def converged(self) -> bool:
        """True if the convergence test passed after all refinement stages."""
    @property
    def stop_reason(self) -> str:
        """'converged', 'max_iterations', 'no_correspondences' or 'diverged'."""
    @property
    def message(self) -> str:
        """One line on why it stopped."""
    @property
    def iterations(self) -> int:
        """Mini-batches processed."""
    @property
    def points_processed(self) -> int:
        """Source points drawn (iterations x batch size)."""
    @property
    def stages(self) -> int:
        """Stationary stages completed."""
    @property
    def evaluated_points(self) -> int:
        """Source points (strided sample) in the final inlier statistics."""
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
    def time_ms(self) -> float:
        """Wall time of the registration, milliseconds (KD-tree build excluded)."""
    @property
    def constraint_ratio(self) -> float:
        """Smallest over largest eigenvalue of the point-to-plane information matrix of the final
        inlier pairs (scaled space); near 0, some motion is not constrained by the data."""
    @property
    def degenerate(self) -> bool:
        """constraint_ratio below the threshold: the transform is not trustworthy along some
        motion (see message)."""
    @property
    def build_ms(self) -> float:
        """Wall time of the KD-tree build (and reference normals/covariances) for an array
        reference, milliseconds (0 for a ReferenceIndex)."""
    @property
    def source_points(self) -> int:
        """Finite source points used."""
    @property
    def source_non_finite_dropped(self) -> int:
        """Source rows dropped for a NaN or infinite coordinate."""
    @property
    def reference_points(self) -> int:
        """Finite reference points indexed."""
    @property
    def reference_non_finite_dropped(self) -> int:
        """Reference rows dropped for a NaN or infinite coordinate."""
    @property
    def trace(self) -> Trace:
        """Per-iteration trace; empty unless record_trace=True."""


def register(
    source: _Points,
    reference: Union[_Points, ReferenceIndex],
    init: _Transform | None = None,
    settings: Settings | BatchSettings | None = None,
    method: _MethodName = "sgd",
    *,
    batch_size: int = ...,
    optimizer: _OptimizerName = ...,
    learning_rate: float = ...,
    max_distance: _DistanceValue = ...,
    max_distance_unit: _UnitName = ...,
    max_iterations: int = ...,
    seed: int = ...,
    momentum: float = ...,
    beta1: float = ...,
    beta2: float = ...,
    rms_decay: float = ...,
    epsilon: float = ...,
    hessian_decay: float = ...,
    damping: float = ...,
    window: int = ...,
    chi2: float = ...,
    path_efficiency: float = ...,
    translation_tolerance: float = ...,
    rotation_tolerance: float = ...,
    refine_stages: int = ...,
    step_decay: float = ...,
    distance_factor: float = ...,
    min_distance: _DistanceValue = ...,
    average: bool = ...,
    scaling_origin: _OriginName = ...,
    cost: _CostName = ...,
    kernel: _KernelName = ...,
    kernel_scale: _DistanceValue = ...,
    trim: float = ...,
    neighbors: int = ...,
    check_degeneracy: bool = ...,
    evaluation_points: int = ...,
    record_trace: bool = ...,
) -> RegistrationResult:
    """Registers `source` to `reference` with SGD-ICP or a batch ICP method; the GIL is released
    while it runs.

    Args:
        source: (N, 3) float32/float64 array, metres, any memory layout: the cloud that moves.
            Copied once into float32; rows with a NaN or inf are dropped and counted.
        reference: (M, 3) array like `source`, or a ReferenceIndex (built once, reusable, also
            from several threads at once). A ReferenceIndex must have the normals / covariances
            of the method's cost: build it with ReferenceIndex(points, cost=...).
        init: initial T_reference_source, (4, 4) rigid; default None = identity.
        settings: base settings: a Settings for the SGD methods (default None = Settings()), a
            BatchSettings for the batch methods (default None = BatchSettings(); the method sets
            its cost).
        method: the CLI's --method. 'sgd' (SGD-ICP with the settings' cost, point-to-point by
            default), 'sgd-plane' / 'sgd-gicp' (SGD-ICP on point-to-plane / plane-to-plane),
            'icp' (batch point-to-point, closed-form SVD step), 'icp-plane' / 'gicp' (batch
            point-to-plane / plane-to-plane, Levenberg-Marquardt). All but 'sgd' set the cost
            (cost= is then an error). Default 'sgd'.

        The batch methods take only max_distance (default 0.05 scaled), max_distance_unit,
        max_iterations (100), kernel, kernel_scale, trim, neighbors, damping (the initial
        Levenberg-Marquardt damping, default 1e-6), translation_tolerance (1e-5 scaled units),
        rotation_tolerance (1e-5 rad), evaluation_points, check_degeneracy and record_trace; the
        defaults below are those of the SGD methods.

        batch_size: source points per mini-batch (m). Default 160.
        optimizer: 'sgd', 'momentum', 'rmsprop', 'adam' or 'gauss-newton'. Default 'adam'.
            Also sets learning_rate to that rule's usual value (sgd 2, momentum 2 * (1 - momentum),
            adam/rmsprop 0.01, gauss-newton 1) unless learning_rate is given too.
        learning_rate: step size alpha, scaled units. Default 0.01.
        max_distance: d_max, pairs farther apart are rejected; a number in max_distance_unit or a
            Distance. Default 0.5 (scaled).
        max_distance_unit: unit of max_distance, min_distance and kernel_scale given as numbers:
            'scaled' (fraction of the largest side of the joint bounding box) or 'm'. Default
            'scaled'.
        max_iterations: iteration limit; reaching it means not converged. Default 4000.
        seed: seed of the mini-batch sampler. Default 2019.
        momentum: heavy-ball velocity decay, [0, 1). Default 0.9.
        beta1: Adam gradient-mean decay, [0, 1). Default 0.9.
        beta2: Adam squared-gradient-mean decay, [0, 1). Default 0.999.
        rms_decay: RMSProp squared-gradient-mean decay, [0, 1). Default 0.9.
        epsilon: Adam/RMSProp denominator offset, scaled units. Default 1e-8.
        hessian_decay: Gauss-Newton matrix averaging, [0, 1). Default 0.9.
        damping: Gauss-Newton relative Levenberg damping. Default 1e-3.
        window: iterations per convergence test window, >= 8. Default 20.
        chi2: critical chi-square value of the test; larger stops earlier. Default 12.59.
        path_efficiency: largest net/total path ratio of a stationary window, (0, 1]. Default 0.5.
        translation_tolerance: absolute stationarity test on each step, scaled units. Default 1e-6.
        rotation_tolerance: ... and on the angles, rad. Default 1e-6.
        refine_stages: refinement stages after the coarse phase (0 = the paper). Default 3.
        step_decay: step multiplier per refinement stage, (0, 1]. Default 0.5.
        distance_factor: refined d_max = factor x median pair distance. Default 3.
        min_distance: floor of d_max; a number in max_distance_unit or a Distance. Default 1e-4
            (scaled).
        average: return the mean of the final stage's iterates (True) or the last one. Default
            True.
        scaling_origin: 'center' or 'lower_corner' (the paper). Default 'center'.
        cost: 'point-to-point' (the paper), 'point-to-plane' or 'plane-to-plane' (GICP). The plane
            costs need reference normals / covariances: estimated here for an array reference, or
            by ReferenceIndex(points, cost=...). Default 'point-to-point'.
        kernel: robust kernel 'none', 'huber', 'cauchy', 'geman-mcclure' or 'welsch'. Default
            'none'.
        kernel_scale: residual size where the kernel starts to down-weight; a number in
            max_distance_unit or a Distance. Default 0.01 (scaled).
        trim: keep this fraction of each mini-batch's pairs, the closest (trimmed ICP), (0, 1].
            Default 1.
        neighbors: neighbours per point for normals and covariances, [3, 1000]. Default 20.
        check_degeneracy: report degenerate geometry in result.constraint_ratio / degenerate.
            Default True.
        evaluation_points: source points for the final inlier statistics, 0 = all. Default 2000.
        record_trace: fill result.trace. Default False.

    Raises:
        InvalidInputError: (a ValueError) wrong shape or dtype, no finite points, fewer source
            points than batch_size, a non-rigid init, a ReferenceIndex without the normals /
            covariances of the method's cost.
        InvalidSettingsError: (a ValueError) an invalid setting or an unknown method.
        TypeError: an unknown keyword, a keyword of the other solver, or a value of the wrong
            type.
    """


# ---- preprocessing


def voxel_downsample(points: _Points, voxel_size_m: float) -> npt.NDArray[np.float32]:
    """One point per occupied cubic voxel of side voxel_size_m (metres): the centroid of the
    points in it, in the order of each voxel's first point (deterministic).

    Args:
        points: (N, 3) float32/float64 array, metres; rows with a NaN or inf are dropped first.
            May be empty.
        voxel_size_m: voxel side, metres, positive and finite.

    Returns:
        (M, 3) float32 array, metres, M <= N.

    Raises:
        InvalidSettingsError: (a ValueError) voxel_size_m not positive and finite, or too small.
        InvalidInputError: (a ValueError) not an (N, 3) float32/float64 array.
    """


def random_downsample(points: _Points, count: int, seed: int = 2019) -> npt.NDArray[np.float32]:
    """`count` distinct points chosen uniformly at random without replacement, in input order.

    Args:
        points: (N, 3) float32/float64 array, metres; rows with a NaN or inf are dropped first.
            May be empty.
        count: points to keep, >= 0; count >= N keeps all.
        seed: seed of the draw; the same input, count and seed give the same points on any
            platform. Default 2019.

    Returns:
        (min(count, N), 3) float32 array, metres.
    """


def estimate_normals(
    points: _Points,
    k: int = 20,
    num_threads: int = 0,
    *,
    viewpoint: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """Unit normals (PCA of the k nearest neighbours, the point included), flipped to face
    `viewpoint`; (0, 0, 0) for degenerate (identical or collinear) neighbourhoods.

    Args:
        points: (N, 3) float32/float64 array, metres; every row must be finite.
        k: neighbours per point, in [3, 1000]. Default 20.
        num_threads: worker threads, 0 = all cores (same results for any count). Default 0.
        viewpoint: (3,) point in metres the normals face; None = the origin. Default None.

    Returns:
        (N, 3) float32 array, one normal per input row.

    Raises:
        InvalidInputError: (a ValueError) bad array, no rows, or a non-finite row.
        InvalidSettingsError: (a ValueError) k or num_threads out of range.
    """


def estimate_covariances(
    points: _Points,
    k: int = 20,
    num_threads: int = 0,
    *,
    regularize: bool = True,
    epsilon: float = 1e-3,
) -> npt.NDArray[np.float32]:
    """Local covariances of the k nearest neighbours (the point included): raw (1/n, m^2) or, with
    regularize=True, the unitless GICP plane model V diag(epsilon, 1, 1) V^T (identity for
    degenerate neighbourhoods).

    Args:
        points: (N, 3) float32/float64 array, metres; every row must be finite.
        k: neighbours per point, in [3, 1000]. Default 20.
        num_threads: worker threads, 0 = all cores (same results for any count). Default 0.
        regularize: return the plane model instead of the raw covariance. Default True.
        epsilon: variance along the normal in the plane model, in (0, 1]. Default 1e-3.

    Returns:
        (N, 3, 3) float32 array of symmetric matrices, one per input row.

    Raises:
        InvalidInputError: (a ValueError) bad array, no rows, or a non-finite row.
        InvalidSettingsError: (a ValueError) k, num_threads or epsilon out of range.
    """


# ---- files


class ReadResult:
    """A point cloud read from a file, with its counts."""

    @property
    def points(self) -> npt.NDArray[np.float32]:
        """(N, 3) finite points, in file order, metres."""
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
    .f32; docs/io.md).

    Args:
        path: the file.
        format: 'auto' (from the extension, the default), 'pcd', 'ply', 'kitti_bin', 'xyz', 'vtk'
            or 'f32'.

    Raises:
        IoError: (an OSError) the file cannot be opened or read.
        FormatError: (a ValueError) the content is not valid for its format.
    """


def read_points(path: _Path, format: str = "auto") -> npt.NDArray[np.float32]:
    """Reads a point-cloud file into an (N, 3) float32 array (metres) of its finite points; see
    read_point_cloud for the formats, the counts and the errors."""


def write_points(
    path: _Path, points: _Points, format: str = "auto", encoding: str = "binary"
) -> None:
    """Writes an (N, 3) float32/float64 array (converted to float32) as PLY, PCD or XYZ.

    Args:
        path: the file; its extension chooses the format unless `format` is given.
        points: (N, 3) float32/float64 array, metres.
        format: 'auto' (default), 'ply', 'pcd' or 'xyz'.
        encoding: 'binary' (default) or 'ascii'; XYZ is always text.

    Raises:
        IoError: (an OSError) the file cannot be written.
        FormatError: (a ValueError) an unknown or read-only format.
    """


# ---- metrics


def translation_error(T_est: _Transform, T_gt: _Transform) -> float:
    """|t_est - t_gt| of two (4, 4) transforms, in their unit (metres)."""


def rotation_error_geodesic(T_est: _Transform, T_gt: _Transform) -> float:
    """Angle of the relative rotation R_est^T R_gt of two (4, 4) transforms, radians in [0, pi]."""


def rotation_error_euler_sum(T_est: _Transform, T_gt: _Transform) -> float:
    """The paper's rotation error: |d roll| + |d pitch| + |d yaw| of two (4, 4) transforms, each
    wrapped to (-pi, pi], radians."""
