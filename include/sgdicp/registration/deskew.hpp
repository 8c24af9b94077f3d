#pragma once
// Registration of a sweep whose points were measured while the sensor moved (a spinning LiDAR
// carried or driven: 0.1 s per sweep), with each point's time: the pose and the sensor's
// velocity within the sweep estimated together (continuous time, constant velocity), so that the
// sweep is compensated ("deskewed") as it is registered. docs/registration.md, "Moving sensors".
//
// The model: the sensor's pose at time t is T(t) = T_reference_source * Exp((t - t_mid) xi), xi
// the sensor's velocity (a twist in its own frame, per second: translation m/s first, then
// rotation rad/s), t_mid the middle of the sweep's times. Point i, measured at time t_i in the
// sensor's frame of that instant, lies at T(t_i) p_i in the reference.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp {

/// The sensor's velocity within a sweep: translation (m/s) first, then rotation (rad/s), in the
/// sensor's frame.
using Twist = Eigen::Matrix<double, 6, 1>;

/// Exp of the twist `xi` (translation first): the rigid motion of a constant velocity xi over
/// one unit of time.
[[nodiscard]] Eigen::Matrix4d exp_twist(const Twist& xi);

struct DeskewSettings {
  /// Source points (a seeded random subset, exact times kept) each iteration looks at.
  std::size_t sample_points = 8000;
  std::size_t max_iterations = 40;
  /// Correspondence distance of the first iteration, metres; later ones take three times the
  /// median distance of the last pairs, never more than the one before.
  double max_correspondence_distance_m = 1.0;
  std::uint64_t seed = 1;
};

struct DeskewedRegistration {
  Eigen::Matrix4d T_reference_source = Eigen::Matrix4d::Identity();  ///< T(t_mid)
  Twist velocity = Twist::Zero();  ///< xi, in the sensor's frame, per second
  double mid_time_s = 0.0;         ///< t_mid: the middle of the sweep's times
  bool converged = false;
  std::size_t iterations = 0;
  double inlier_rmse_m = 0.0;  ///< point-to-plane, of the last iteration's pairs
  std::string message;
};

/// Registers the sweep `source` (times_s: one per point, seconds, any origin) to `reference`,
/// whose cloud must carry normals (prepare_reference with a plane cost gives them), from
/// T_init (a rigid registration's pose: the pose of the sweep's middle, about). A sweep whose
/// times are all equal is rigid: T_init is returned as is, velocity zero. Throws
/// InvalidInputError for a count of times that is not the source's, a non-finite time, a
/// reference without normals or a source with fewer than 6 finite points.
[[nodiscard]] DeskewedRegistration align_deskewed(const PointCloud& source,
                                                  std::span<const float> times_s,
                                                  const ReferenceIndex& reference,
                                                  const Eigen::Matrix4d& T_init,
                                                  const DeskewSettings& settings = {});

/// align_deskewed against a reference cloud: its index built as a registration builds it
/// (reference_index_for with the defaults), with the normals the pairs read. Throws as above.
[[nodiscard]] DeskewedRegistration align_deskewed(const PointCloud& source,
                                                  std::span<const float> times_s,
                                                  const PointCloud& reference,
                                                  const Eigen::Matrix4d& T_init,
                                                  const DeskewSettings& settings = {});

/// log of a rigid motion: the twist xi with exp_twist(xi) == T (rotation below pi).
[[nodiscard]] Twist log_twist(const Eigen::Matrix4d& T);

/// The frame's points moved to where they would be had the whole sweep been measured at its
/// middle, the sensor moving by `sweep_motion` from the sweep's first time to its last (constant
/// velocity: KISS-ICP's deskewing): p' = Exp((s - 1/2) log(sweep_motion)) p, s the point's time
/// in [0, 1] over the sweep. A frame without times, or whose times are all equal, is returned as
/// it is. Times and everything else of the frame are kept.
[[nodiscard]] PointCloud deskewed_by_motion(const PointCloud& frame,
                                            const Eigen::Matrix4d& sweep_motion);

/// Times for a sweep of a spinning LiDAR stored without them (KITTI's .bin): each point's
/// azimuth seen from the sensor, as the sensor turns clockwise seen from above (z up; KITTI's
/// Velodyne) through one sweep of sweep_s seconds, from the -x axis (behind a KITTI car: the
/// seam) through +y, +x and -y back to it: s = (1 - atan2(y, x) / pi) / 2, time s * sweep_s
/// (KISS-ICP's rule for KITTI).
[[nodiscard]] std::vector<float> azimuth_times_s(const PointCloud& frame, double sweep_s = 0.1);

/// The sensor's pose at time t_s (T(t) above).
[[nodiscard]] Eigen::Matrix4d pose_at(const DeskewedRegistration& r, double t_s);

/// Every point of `source`, in input order, moved by the pose at its own time: the sweep
/// compensated and in the reference frame.
[[nodiscard]] PointCloud deskewed_in_reference(const PointCloud& source,
                                               std::span<const float> times_s,
                                               const DeskewedRegistration& r);

}  // namespace sgdicp
