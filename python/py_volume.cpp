// nimbus.Volume (docs/python.md, "Volumes"): a dense float32 numpy array becomes an OpenVDB grid (the
// voxels equal to 0 left inactive), converted once to NanoVDB as a volume file is (io/vdb_openvdb_dense.cpp,
// in the OpenVDB module, loaded on first use), so that a scene renders it exactly as it renders the same
// grid written to a .vdb.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <optional>

#include "io/vdb.h"
#include "io/vdb_internal.h"
#include "media/density_grid.h"
#include "nimbus/error.h"
#include "py_common.h"

namespace nimbus::python {

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

std::array<double, 3> voxel_sizes(const py::object& voxel_size) {
  std::array<double, 3> vs{};
  if (py::isinstance<py::float_>(voxel_size) || py::isinstance<py::int_>(voxel_size)) {
    vs.fill(voxel_size.cast<double>());
  } else {
    const auto v = voxel_size.cast<std::vector<double>>();
    if (v.size() != 3) throw Error("Volume: voxel_size must be a number or three numbers (x, y, z)");
    vs = {v[0], v[1], v[2]};
  }
  for (double s : vs)
    if (!(s > 0.0) || !std::isfinite(s))
      throw Error(fmt::format("Volume: voxel_size must be > 0 (got {})", s));
  return vs;
}

using BoolArray = py::array_t<bool, py::array::c_style | py::array::forcecast>;

// The first non-finite value's index, as an error (OpenVDB would take NaN for the background, 0).
void check_finite(const FloatArray& a) {
  const float* p = a.data();
  const size_t n = size_t(a.size());
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) {
      const size_t nz = size_t(a.shape(2)), ny = size_t(a.shape(1));
      throw Error(fmt::format("Volume: density[{}, {}, {}] is {} (values must be finite)", i / (ny * nz),
                              (i / nz) % ny, i % nz, p[i]));
    }
}

Volume make_volume(const FloatArray& a, const py::object& voxel_size, const std::array<double, 3>& origin,
                   const std::array<int, 3>& index_offset, const std::string& name,
                   const std::optional<BoolArray>& active) {
  if (a.ndim() != 3) throw Error(fmt::format("Volume: the array must be 3-D (x, y, z), not {}-D", a.ndim()));
  for (int d = 0; d < 3; ++d) {
    if (a.shape(d) < 1) throw Error("Volume: the array is empty");
    if (std::abs(int64_t(index_offset[d])) + a.shape(d) > (int64_t(1) << 30))
      throw Error("Volume: voxel indices must stay within +-2^30");
  }
  for (double o : origin)
    if (!std::isfinite(o)) throw Error("Volume: origin must be finite");
  const std::array<double, 3> vs = voxel_sizes(voxel_size);
  if (active && (active->ndim() != 3 || active->shape(0) != a.shape(0) || active->shape(1) != a.shape(1) ||
                 active->shape(2) != a.shape(2)))
    throw Error("Volume: `active` must have the density array's shape");
  Volume v;
  v.name = name;
  py::gil_scoped_release release;
  check_finite(a);
  const detail::DenseVolume dense{.values = a.data(),
                                  .shape = {int(a.shape(0)), int(a.shape(1)), int(a.shape(2))},
                                  .voxel_size = vs,
                                  .origin = origin,
                                  .index_offset = index_offset,
                                  .name = name,
                                  .active = active ? active->data() : nullptr};
  detail::DenseGrid grid = detail::openvdb_grid_from_dense(dense);
  if (grid.active_voxels == 0) throw Error("Volume: every voxel is 0 (an empty grid)");
  v.grid = std::make_shared<const DensityGrid>(
      DensityGrid::from_nanovdb(std::move(grid.nano), fmt::format("numpy volume '{}'", name)));
  v.openvdb_grid = std::move(grid.grid);
  return v;
}

Volume volume_from_file(const std::filesystem::path& path, const std::string& grid) {
  Volume v;
  py::gil_scoped_release release;
  v.grid = std::make_shared<const DensityGrid>(load_density_grid(path, grid));
  v.name = v.grid->stats().name;
  return v;
}

// The voxel values over the active index bbox, as an [x, y, z] array (raw values, negatives kept).
py::array_t<float> dense_values(const Volume& v) {
  const auto& st = v.grid->stats();
  const std::array<int, 3> lo = st.index_min, hi = st.index_max;
  const std::vector<py::ssize_t> shape = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  py::array_t<float> out(shape);
  float* p = out.mutable_data();
  py::gil_scoped_release release;
  auto acc = v.grid->nano_grid().getAccessor();
  for (int i = lo[0]; i <= hi[0]; ++i)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int k = lo[2]; k <= hi[2]; ++k) *p++ = acc.getValue(nanovdb::Coord(i, j, k));
  return out;
}

// The activity of the voxels of dense_values().
py::array_t<bool> active_mask(const Volume& v) {
  const auto& st = v.grid->stats();
  const std::array<int, 3> lo = st.index_min, hi = st.index_max;
  py::array_t<bool> out(std::vector<py::ssize_t>{hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1});
  bool* p = out.mutable_data();
  py::gil_scoped_release release;
  auto acc = v.grid->nano_grid().getAccessor();
  for (int i = lo[0]; i <= hi[0]; ++i)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int k = lo[2]; k <= hi[2]; ++k) *p++ = acc.isActive(nanovdb::Coord(i, j, k));
  return out;
}

// The index-to-world matrix's diagonal when it has no rotation or shear (exactly the voxel size the
// grid was made with), else the lengths NanoVDB reports.
std::array<double, 3> voxel_size_of(const Volume& v) {
  const auto& m = v.grid->nano_grid().map().mMatD;
  if (m[1] == 0 && m[2] == 0 && m[3] == 0 && m[5] == 0 && m[6] == 0 && m[7] == 0) return {m[0], m[4], m[8]};
  const Vec3 s = v.grid->stats().voxel_size;
  return {s.x, s.y, s.z};
}

void save_vdb(const Volume& v, const std::filesystem::path& path) {
  if (!v.openvdb_grid) throw Error("Volume.save: only a volume made from a numpy array can be saved");
  py::gil_scoped_release release;
  detail::save_openvdb_grid(v.openvdb_grid, path);
}

std::array<double, 3> tuple3(const Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

void init_volume(py::module_& m) {
  py::class_<Volume>(m, "Volume", R"(A density grid in memory, for a scene's vdb shape.

Volume(density, voxel_size=1.0, origin=(0, 0, 0), index_offset=(0, 0, 0), name='density', active=None)

density: a 3-D float32 array indexed [x, y, z] (C order: z varies fastest), density[i, j, k] the value
  of voxel (i, j, k) + index_offset. Voxels equal to 0 are left out (inactive), as in a fog volume.
voxel_size: world units per voxel, a number or (x, y, z).
origin: the world position of voxel index (0, 0, 0) (OpenVDB's convention: a voxel's value sits at its
  index point, the centre of its cell). World = origin + voxel_size * index.
active: optionally a bool array of the same shape: which voxels are active (default: the non-zero ones);
  an inactive voxel keeps its value.
The array is converted once, through OpenVDB, to NanoVDB, exactly as a .vdb file is when a scene
loads it: a scene renders the Volume bit for bit as it renders the same grid saved with save().
In a scene dict: {'type': 'vdb', 'volume': vol} (or a name given in scene_from_dict's volumes=); the
shape's 'scale' and 'translate' and the medium's 'transform' apply as to a file.)")
      .def(py::init(&make_volume), py::arg("density"), py::arg("voxel_size") = 1.0,
           py::arg("origin") = std::array<double, 3>{0, 0, 0},
           py::arg("index_offset") = std::array<int, 3>{0, 0, 0}, py::arg("name") = "density",
           py::arg("active") = py::none())
      .def_static("from_file", &volume_from_file, py::arg("path"), py::arg("grid") = "",
                  "The float grid `grid` (default: the first) of a .vdb or .nvdb file.")
      .def("save", &save_vdb, py::arg("path"),
           "Writes the grid as an OpenVDB (.vdb) file (a volume made from numpy only).")
      .def("to_numpy", &dense_values,
           "The voxel values over the active index box [index_min, index_max] as a float32 [x, y, z] "
           "array: Volume(v.to_numpy(), v.voxel_size, v.origin, v.index_min, active=v.active_mask()) "
           "rebuilds the grid.")
      .def("active_mask", &active_mask, "Which voxels of to_numpy() are active (a bool [x, y, z] array).")
      .def_readonly("name", &Volume::name)
      .def_property_readonly("voxel_size", &voxel_size_of, "World units per voxel (x, y, z)")
      .def_property_readonly(
          "origin",
          [](const Volume& v) {
            const auto& t = v.grid->nano_grid().map().mVecD;
            return std::array<double, 3>{t[0], t[1], t[2]};
          },
          "World position of voxel index (0, 0, 0)")
      .def_property_readonly(
          "index_min", [](const Volume& v) { return v.grid->stats().index_min; },
          "Lowest active voxel index (x, y, z)")
      .def_property_readonly(
          "index_max", [](const Volume& v) { return v.grid->stats().index_max; },
          "Highest active voxel index (x, y, z), inclusive")
      .def_property_readonly("active_voxels", [](const Volume& v) { return v.grid->stats().active_voxels; })
      .def_property_readonly(
          "min", [](const Volume& v) { return v.grid->stats().min_value; }, "Smallest active value")
      .def_property_readonly(
          "max", [](const Volume& v) { return v.grid->stats().max_value; }, "Largest active value")
      .def_property_readonly(
          "bounds",
          [](const Volume& v) {
            const Bounds b = v.grid->world_bounds();
            return std::make_pair(tuple3(b.lo), tuple3(b.hi));
          },
          "World bounds of the data ((x0, y0, z0), (x1, y1, z1)), one voxel beyond the active ones")
      .def("__repr__", [](const Volume& v) {
        const auto& st = v.grid->stats();
        return fmt::format("<nimbus.Volume '{}' {} active voxels, index [{}, {}, {}]..[{}, {}, {}]>", v.name,
                           st.active_voxels, st.index_min[0], st.index_min[1], st.index_min[2],
                           st.index_max[0], st.index_max[1], st.index_max[2]);
      });
}

}  // namespace nimbus::python
