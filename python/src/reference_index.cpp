// sgd_icp.ReferenceIndex: a KD-tree over a reference cloud (with the normals or covariances a
// cost needs), built once with the GIL released and shared by every registration that uses it.
#include <chrono>
#include <memory>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp::python {

using namespace pybind11::literals;

/// Builds the index with `build`, with the GIL released, and times it.
std::shared_ptr<SharedIndex> build_index(ConvertedCloud&& converted, const IndexBuilder& build) {
  const py::gil_scoped_release release;
  const auto start = std::chrono::steady_clock::now();
  ReferenceIndex index = build(std::move(converted.cloud));
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return std::make_shared<SharedIndex>(
      SharedIndex{std::move(index), converted.non_finite_dropped, ms});
}

/// The error of check_reference_prepared, in the words of the Python API.
void check_prepared(const SharedIndex& shared, CostType cost) {
  const PointCloud& cloud = shared.index.cloud();
  if ((needs_reference_normals(cost) && !cloud.has_normals()) ||
      (needs_covariances(cost) && !cloud.has_covariances())) {
    throw InvalidInputError("the " + std::string(to_string(cost)) + " cost needs reference " +
                            (needs_covariances(cost) ? "covariances" : "normals") +
                            ": build the index with ReferenceIndex(points, cost='" +
                            std::string(to_string(cost)) +
                            "'), or pass the reference points as an array");
  }
}

void bind_reference_index(py::module_& m) {
  py::class_<SharedIndex, std::shared_ptr<SharedIndex>>(
      m, "ReferenceIndex",
      "A KD-tree over a reference cloud, built once and reused by any number of registrations, "
      "also from several threads at once (queries are read-only).")
      .def(py::init([](const py::handle& points, const py::handle& normals,
                       const py::handle& leaf_size, const py::handle& cost,
                       const py::handle& neighborhood, const py::handle& threads) {
             const CostType c = cost_from_object(cost, "cost");
             const NeighborhoodSettings n = neighborhood.is_none()
                                                ? NeighborhoodSettings{}
                                                : py::cast<NeighborhoodSettings>(neighborhood);
             auto converted =
                 cloud_from_array(points, "reference", NonFinite::drop, false, normals);
             const KdTreeSettings tree{as_count(leaf_size, "leaf_size"),
                                       as_count(threads, "threads")};
             return build_index(std::move(converted), [&](PointCloud cloud) {
               ReferenceIndex index(std::move(cloud), tree);
               prepare_reference(index, c, n);
               return index;
             });
           }),
           "points"_a, py::kw_only(), "normals"_a = py::none(),
           "leaf_size"_a = KdTreeSettings{}.leaf_size, "cost"_a = "point-to-point",
           "neighborhood"_a = py::none(), "threads"_a = KdTreeSettings{}.num_threads,
           "Builds the tree over an (N, 3) float32/float64 array of points in metres (copied "
           "once into float32 storage; rows with a NaN or infinite coordinate are dropped and "
           "counted in non_finite_dropped), or over an Open3D PointCloud (legacy or tensor; its "
           "normals too when it has them). normals: (N, 3) unit normals, one per row of points, "
           "default None; the point-to-plane cost uses them instead of estimating its own. "
           "leaf_size: points per KD-tree leaf, default 24. threads: threads of the build, "
           "default 1, 0 = every core (the same tree for any count). "
           "cost: the cost the index will serve, default 'point-to-point'; 'point-to-plane' "
           "estimates the reference normals (unless given), 'plane-to-plane' the covariances, with "
           "`neighborhood` (NeighborhoodSettings, default None = NeighborhoodSettings(): plain "
           "k-nearest "
           "neighbourhoods, as the batch methods' defaults; pass Settings().neighborhood to give "
           "the SGD methods the normals they would estimate themselves). The GIL "
           "is released during the build. The index never changes afterwards: the SGD methods "
           "estimate the normals or covariances they use during the run; a batch method whose "
           "cost needs them raises InvalidInputError when the index lacks them.")
      .def_static(
          "for_registration",
          [](const py::handle& points, const py::handle& method, const py::handle& settings,
             const py::kwargs& overrides) {
            const ReferenceNeeds needs =
                reference_needs(method_from_object(method), settings, overrides);
            return build_index(cloud_from_array(points, "reference", NonFinite::drop), needs.build);
          },
          "points"_a, py::kw_only(), "method"_a = "sgd", "settings"_a = py::none(),
          "The index that register(source, points, method=method, settings=settings, "
          "**overrides) builds for its reference (for a batch method the cost's normals or "
          "covariances with the settings' neighbourhood), for reuse over many sources with the "
          "same arguments: the results are the same as passing points each time. points: an "
          "array or an Open3D PointCloud, as for register(). The global_* keywords of "
          "init='global' are checked and leave the index as it is. Raises the errors of "
          "register() for the method, settings and keywords.")
      .def("__len__", [](const SharedIndex& s) { return s.index.size(); })
      .def_property_readonly(
          "points",
          [](const py::object& self) {
            return readonly_view(self.cast<const SharedIndex&>().index.cloud(), self);
          },
          "The indexed points: a read-only (N, 3) float32 view (no copy); a float64 copy for "
          "georeferenced points.")
      .def_property_readonly(
          "voxel_size_m", [](const SharedIndex& s) { return s.index.voxel_size_m(); },
          "The voxel grid the points were thinned with before indexing, metres (0 = indexed as "
          "given); registrations against the index thin their source on the same grid.")
      .def_property_readonly(
          "non_finite_dropped", [](const SharedIndex& s) { return s.non_finite_dropped; },
          "Rows of the input dropped for a NaN or infinite coordinate.")
      .def_property_readonly(
          "build_ms", [](const SharedIndex& s) { return s.build_ms; },
          "Wall time of the KD-tree build (and of the normals or covariances), milliseconds.")
      .def_property_readonly(
          "has_normals", [](const SharedIndex& s) { return s.index.cloud().has_normals(); },
          "Whether the reference has normals (built with cost='point-to-plane' or "
          "'plane-to-plane').")
      .def_property_readonly(
          "has_covariances", [](const SharedIndex& s) { return s.index.cloud().has_covariances(); },
          "Whether the reference has covariances (built with cost='plane-to-plane').")
      .def_property_readonly(
          "bounding_box",
          [](const SharedIndex& s) {
            const BoundingBox& box = s.index.bounding_box();
            py::array_t<double> lower(3);
            py::array_t<double> upper(3);
            for (py::ssize_t i = 0; i < 3; ++i) {
              lower.mutable_at(i) = box.min[i];
              upper.mutable_at(i) = box.max[i];
            }
            return py::make_tuple(lower, upper);
          },
          "(min, max) corners of the axis-aligned bounding box, two (3,) float64 arrays, "
          "metres.")
      .def("__repr__", [](const SharedIndex& s) {
        return "<sgd_icp.ReferenceIndex of " + std::to_string(s.index.size()) + " points (" +
               std::to_string(s.non_finite_dropped) + " non-finite rows dropped)>";
      });
}

}  // namespace sgdicp::python
