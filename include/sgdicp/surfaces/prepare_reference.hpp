#pragma once
// A reference index given what a cost reads of it (normals, covariances) before it is shared.
#include "sgdicp/costs/cost.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp {

/// Gives the reference what `cost` needs (cost.hpp: normals for point-to-plane, covariances for
/// plane-to-plane), estimated with estimate_covariances over its own tree, unless it has it
/// already. Not thread-safe: call it before sharing the index between threads.
void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood = {});

/// Throws InvalidInputError when the reference lacks what `cost` needs, saying how to get it.
void check_reference_prepared(const ReferenceIndex& reference, CostType cost);

}  // namespace sgdicp
