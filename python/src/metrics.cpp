// The errors of a transform against the ground truth (translation_error, rotation_error_geodesic,
// rotation_error_euler_sum): the library's metrics, as the CLI and the benchmarks compute them.
#include "sgdicp/metrics/metrics.hpp"
#include "bindings.hpp"

namespace sgdicp::python {

using namespace pybind11::literals;

void bind_metrics(py::module_& m) {
  m.def(
      "translation_error",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return translation_error(matrix_from_array(T_est, "T_est"),
                                 matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a, "|t_est - t_gt| of two (4, 4) transforms, in their unit (metres).");
  m.def(
      "rotation_error_geodesic",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return rotation_error_geodesic(matrix_from_array(T_est, "T_est"),
                                       matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a,
      "Angle of the relative rotation R_est^T R_gt of two (4, 4) transforms, radians in [0, "
      "pi].");
  m.def(
      "rotation_error_euler_sum",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return rotation_error_euler_sum(matrix_from_array(T_est, "T_est"),
                                        matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a,
      "The paper's rotation error: |d roll| + |d pitch| + |d yaw| of two (4, 4) transforms, "
      "each wrapped to (-pi, pi], radians.");
}

}  // namespace sgdicp::python
