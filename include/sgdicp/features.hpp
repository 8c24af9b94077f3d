#pragma once
// What a cost needs from the reference besides its points: normals (point-to-plane) or
// covariances (plane-to-plane), estimated over the reference's own KD-tree.
#include "sgdicp/cost.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/preprocessing.hpp"

namespace sgdicp {

/// Gives the reference what `cost` needs, estimated with `neighborhood`, unless it has it already.
/// Not thread-safe: call it before sharing the index between threads.
void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood = {});

/// Throws InvalidInputError when the reference lacks what `cost` needs, saying how to get it.
void check_reference_features(const ReferenceIndex& reference, CostType cost);

}  // namespace sgdicp
