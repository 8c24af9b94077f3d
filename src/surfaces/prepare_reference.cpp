#include "sgdicp/surfaces/prepare_reference.hpp"

#include <string>
#include <utility>

#include "sgdicp/core/error.hpp"

namespace sgdicp {

void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood) {
  const PointCloud& cloud = reference.cloud();
  const bool missing = (needs_reference_normals(cost) && !cloud.has_normals()) ||
                       (needs_covariances(cost) && !cloud.has_covariances());
  if (!missing) return;
  // The tree points at the index's own points, so estimate into a copy and hand the results over.
  PointCloud copy;
  copy.points = cloud.points;
  estimate_covariances(copy, reference, neighborhood);
  reference.set_normals_and_covariances(std::move(copy.normals), std::move(copy.covariances));
}

void check_reference_prepared(const ReferenceIndex& reference, CostType cost) {
  const PointCloud& cloud = reference.cloud();
  if ((needs_reference_normals(cost) && !cloud.has_normals()) ||
      (needs_covariances(cost) && !cloud.has_covariances())) {
    throw InvalidInputError("the " + std::string(to_string(cost)) + " cost needs reference " +
                            (needs_covariances(cost) ? "covariances" : "normals") +
                            ": call prepare_reference(index, cost) first (or pass the reference "
                            "cloud to align(), which does it)");
  }
}

}  // namespace sgdicp
