#pragma once
// The registration costs, all in one form. For a pair (source point s moved to q = R s + t,
// reference point r) the residual is e = q - r and the pair costs rho(e^T Omega e): the cost
// only chooses the 3x3 information matrix Omega (a new cost is one more case in
// information_matrix), rho is a robust kernel (robust_kernel.hpp).
//   point-to-point (the paper, Besl-McKay): Omega = I
//   point-to-plane (Chen-Medioni):          Omega = n n^T, n the reference normal
//   plane-to-plane (GICP, Segal et al.):    Omega = (C_r + R C_s R^T)^-1, with the regularised,
//                                           unitless plane covariances (surfaces/normals.hpp)
// Omega is unitless in all three, so the costs live in the unit of the points (metres, or the
// paper's scaled space) and one step size fits them all.
//
// The mini-batch objective and its derivatives (paper eq. 3-7 generalised):
//   F = 1/(4m) sum_i rho(s_i),  g = dF/dtheta = 1/(2m) sum_i w_i J_i^T Omega_i e_i,
//   H = 1/(2m) sum_i w_i J_i^T Omega_i J_i (Gauss-Newton),
// with s_i = e_i^T Omega_i e_i, w_i = rho'(s_i) and J_i = dq_i/dtheta. Omega of plane-to-plane
// depends on R; like every GICP implementation we hold it fixed within an iteration (g is the exact
// gradient of F with Omega frozen).
#include <array>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <Eigen/LU>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/costs/robust_kernel.hpp"

namespace sgdicp {

using PoseMatrix = Eigen::Matrix<double, 6, 6>;
using PoseJacobianMatrix = Eigen::Matrix<double, 3, 6>;

enum class CostType { point_to_point, point_to_plane, plane_to_plane };

inline constexpr std::array<EnumName<CostType>, 3> kCostNames{{
    {CostType::point_to_point, "point-to-point"},
    {CostType::point_to_plane, "point-to-plane"},
    {CostType::plane_to_plane, "plane-to-plane"},
}};
constexpr const auto& enum_names(CostType) {
  return kCostNames;
}
constexpr std::string_view enum_noun(CostType) {
  return "cost";
}

[[nodiscard]] inline std::string_view to_string(CostType t) {
  return enum_name(t);
}
/// Parses a name of kCostNames ('_' for '-' too); throws InvalidSettingsError otherwise.
[[nodiscard]] inline CostType cost_from_string(std::string_view name) {
  return parse_enum<CostType>(name);
}

/// What a cost needs besides the points.
[[nodiscard]] inline bool needs_reference_normals(CostType t) {
  return t == CostType::point_to_plane;
}
[[nodiscard]] inline bool needs_covariances(CostType t) {
  return t == CostType::plane_to_plane;
}

/// Omega of one pair (see the top of this file). `reference_normal` is used by point-to-plane,
/// the covariances and `rotation` by plane-to-plane.
[[nodiscard]] inline Eigen::Matrix3d information_matrix(CostType type,
                                                        const Eigen::Vector3f& reference_normal,
                                                        const Eigen::Matrix3f& reference_covariance,
                                                        const Eigen::Matrix3f& source_covariance,
                                                        const Eigen::Matrix3d& rotation) {
  switch (type) {
    case CostType::point_to_point:
      return Eigen::Matrix3d::Identity();
    case CostType::point_to_plane: {
      const Eigen::Vector3d n = reference_normal.cast<double>();
      return n * n.transpose();
    }
    case CostType::plane_to_plane: {
      const Eigen::Matrix3d c = reference_covariance.cast<double>() +
                                rotation * source_covariance.cast<double>() * rotation.transpose();
      return c.inverse();
    }
  }
  return Eigen::Matrix3d::Identity();
}

/// dq/dtheta of q = R(roll, pitch, yaw) s + t at a fixed pose: [I | dR/droll s, dR/dpitch s,
/// dR/dyaw s] (paper eq. 6-7).
class EulerPoseJacobian {
 public:
  explicit EulerPoseJacobian(const PoseVector& theta)
      : rotation_(rotation_from_rpy(theta[3], theta[4], theta[5])),
        translation_(theta.head<3>()),
        d_rotation_(rotation_derivatives(theta[3], theta[4], theta[5])) {}

  [[nodiscard]] Eigen::Vector3d transform(const Eigen::Vector3d& s) const {
    return rotation_ * s + translation_;
  }
  // Forced inline: this and the accumulation below sit in the hot loop of every iteration
  // (measured with callgrind: out of line they cost the paper's path 5 %).
  [[nodiscard]] [[gnu::always_inline]] PoseJacobianMatrix jacobian(const Eigen::Vector3d& s) const {
    PoseJacobianMatrix j;
    j.leftCols<3>().setIdentity();
    for (int k = 0; k < 3; ++k) j.col(3 + k) = d_rotation_[k] * s;
    return j;
  }
  [[nodiscard]] const Eigen::Matrix3d& rotation() const noexcept { return rotation_; }

 private:
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d translation_;
  std::array<Eigen::Matrix3d, 3> d_rotation_;
};

/// Accumulates the mini-batch objective F, its gradient g and (on request) the Gauss-Newton
/// matrix H over pairs, with a robust kernel of scale `kernel_scale` (unit of the points).
class CostAccumulator {
 public:
  CostAccumulator(KernelType kernel, double kernel_scale, bool with_hessian)
      : kernel_(kernel), kernel_scale_(kernel_scale), with_hessian_(with_hessian) {}

  /// What one pair adds: w J^T Omega e, w J^T Omega J (when the Hessian is kept) and rho.
  struct PairTerm {
    PoseVector jte;
    PoseMatrix jtj;
    double rho;
  };

  /// The term of a pair with residual e, Jacobian j = de/dtheta and information matrix omega;
  /// a pure function, so terms may be made on any thread and added in order (add(PairTerm)).
  [[nodiscard]] PairTerm term(const PoseJacobianMatrix& j, const Eigen::Vector3d& e,
                              const Eigen::Matrix3d& omega) const {
    const Eigen::Vector3d omega_e = omega * e;
    const double s = e.dot(omega_e);
    const double w = kernel_weight(kernel_, s, kernel_scale_);
    PairTerm t;
    t.jte.noalias() = w * (j.transpose() * omega_e);
    if (with_hessian_) t.jtj.noalias() = w * (j.transpose() * omega * j);
    t.rho = kernel_rho(kernel_, s, kernel_scale_);
    return t;
  }

  /// term() for Omega = n n^T (point-to-plane): of rank one, so J^T Omega e = (J^T n)(n^T e)
  /// and J^T Omega J = (J^T n)(J^T n)^T, a third of the general products' operations (the
  /// bunny's refinement: ~575 instructions a pair with the general term, measured with
  /// callgrind). A zero normal (no plane) gives a zero term, as n n^T = 0 does.
  [[nodiscard]] PairTerm plane_term(const PoseJacobianMatrix& j, const Eigen::Vector3d& e,
                                    const Eigen::Vector3d& normal) const {
    CostAccumulator one(kernel_, kernel_scale_, with_hessian_);
    one.add_plane(j, e, normal);
    return {one.jte_, one.jtj_, one.cost_};
  }

  /// Adds plane_term() at once, the same sums bit for bit without the term in between (a 6x6
  /// written and read again: ~6 % of the bunny's registration, measured with perf).
  [[gnu::always_inline]] void add_plane(const PoseJacobianMatrix& j, const Eigen::Vector3d& e,
                                        const Eigen::Vector3d& normal) {
    const PoseVector jtn = j.transpose() * normal;
    const double r = normal.dot(e);
    const double s = r * r;
    const double w = kernel_weight(kernel_, s, kernel_scale_);
    jte_.noalias() += (w * r) * jtn;
    if (with_hessian_) jtj_.noalias() += (w * jtn) * jtn.transpose();
    cost_ += kernel_rho(kernel_, s, kernel_scale_);
    ++pairs_;
  }

  void add(const PairTerm& t) {
    jte_ += t.jte;
    if (with_hessian_) jtj_ += t.jtj;
    cost_ += t.rho;
    ++pairs_;
  }

  /// Adds a pair with residual e, Jacobian j = de/dtheta and information matrix omega.
  void add(const PoseJacobianMatrix& j, const Eigen::Vector3d& e, const Eigen::Matrix3d& omega) {
    add(term(j, e, omega));
  }

  /// The same for Omega = I without a kernel (the paper's cost): fewer operations in the
  /// hot loop.
  [[gnu::always_inline]] void add_point_to_point(const PoseJacobianMatrix& j,
                                                 const Eigen::Vector3d& e) {
    // The translation block of J is the identity.
    jte_.head<3>() += e;
    jte_.tail<3>().noalias() += j.rightCols<3>().transpose() * e;
    if (with_hessian_) jtj_.noalias() += j.transpose() * j;
    cost_ += e.squaredNorm();
    ++pairs_;
  }

  /// g = 1/(2m) sum w J^T Omega e.
  [[nodiscard]] PoseVector gradient(std::size_t batch_size) const {
    return jte_ / (2.0 * static_cast<double>(batch_size));
  }
  /// H = 1/(2m) sum w J^T Omega J (zero unless requested).
  [[nodiscard]] PoseMatrix hessian(std::size_t batch_size) const {
    return jtj_ / (2.0 * static_cast<double>(batch_size));
  }
  /// F = 1/(4m) sum rho(e^T Omega e).
  [[nodiscard]] double cost(std::size_t batch_size) const {
    return cost_ / (4.0 * static_cast<double>(batch_size));
  }
  [[nodiscard]] std::size_t pairs() const noexcept { return pairs_; }

 private:
  KernelType kernel_;
  double kernel_scale_;
  bool with_hessian_;
  PoseVector jte_ = PoseVector::Zero();
  PoseMatrix jtj_ = PoseMatrix::Zero();
  double cost_ = 0.0;
  std::size_t pairs_ = 0;
};

}  // namespace sgdicp
