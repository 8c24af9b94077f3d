#include "sgdicp/features.hpp"

#include <string>

#include "sgdicp/error.hpp"

namespace sgdicp {

void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood) {
  const PointCloud& cloud = reference.cloud();
  const bool missing = (needs_reference_normals(cost) && !cloud.has_normals()) ||
                       (needs_covariances(cost) && !cloud.has_covariances());
  if (missing) reference.estimate_covariances(neighborhood);
}

void check_reference_features(const ReferenceIndex& reference, CostType cost) {
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
