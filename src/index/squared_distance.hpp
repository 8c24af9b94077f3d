#pragma once
// The squared distance as nanoflann's L2_Simple_Adaptor sums it (query minus point, x then y then
// z, in float), so that every backend of ReferenceIndex and the remembered queries give the
// tree's bits. Private to the library.
#include <Eigen/Core>

namespace sgdicp::detail {

[[nodiscard]] inline float tree_squared_distance(const Eigen::Vector3f& query,
                                                 const Eigen::Vector3f& point) {
  float sum = 0.0F;
  for (Eigen::Index d = 0; d < 3; ++d) {
    const float diff = query[d] - point[d];
    sum += diff * diff;
  }
  return sum;
}

}  // namespace sgdicp::detail
