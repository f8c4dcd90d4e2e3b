// numpy arrays from C++ buffers, and EXR/PNG images (docs/python.md, "Images").
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <filesystem>

#include "nimbus/error.h"
#include "nimbus/image.h"
#include "py_common.h"

namespace nimbus::python {

py::array_t<float> float_array(const std::vector<float>& data, const std::vector<py::ssize_t>& shape) {
  py::array_t<float> a(shape);
  if (size_t(a.size()) != data.size()) throw Error("internal: array size mismatch");
  std::memcpy(a.mutable_data(), data.data(), data.size() * sizeof(float));
  return a;
}

py::array_t<double> double_array(const std::vector<double>& data, const std::vector<py::ssize_t>& shape) {
  py::array_t<double> a(shape);
  if (size_t(a.size()) != data.size()) throw Error("internal: array size mismatch");
  std::memcpy(a.mutable_data(), data.data(), data.size() * sizeof(double));
  return a;
}

namespace {

py::dict read_exr_py(const std::filesystem::path& path) {
  ImageMetadata meta;
  Image img;
  {
    py::gil_scoped_release release;
    img = read_exr(path, &meta);
  }
  const size_t n = size_t(img.width) * img.height;
  const int k = img.alpha.empty() ? 3 : 4;
  std::vector<float> data(n * k);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) data[i * k + c] = img.rgb[i * 3 + c];
    if (k == 4) data[i * 4 + 3] = img.alpha[i];
  }
  py::dict out;
  out["rgba"] = float_array(data, {img.height, img.width, k});
  py::dict m;
  for (const auto& [key, value] : meta) m[py::str(key)] = value;
  out["metadata"] = m;
  return out;
}

void write_image_py(const std::filesystem::path& path,
                    const py::array_t<float, py::array::c_style | py::array::forcecast>& a, double exposure) {
  if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4))
    throw Error("write_image: the pixels must be an H x W x 3 or H x W x 4 array");
  Image img(int(a.shape(1)), int(a.shape(0)));
  const int k = int(a.shape(2));
  const size_t n = size_t(img.width) * img.height;
  const float* p = a.data();
  if (k == 4) img.alpha.resize(n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) img.rgb[i * 3 + c] = p[i * k + c];
    if (k == 4) img.alpha[i] = p[i * 4 + 3];
  }
  py::gil_scoped_release release;
  write_image(path, img, {}, exposure);
}

}  // namespace

void init_image(py::module_& m) {
  m.def("read_exr", &read_exr_py, py::arg("path"),
        "Reads an EXR's R, G, B (and A when present) channels: {'rgba': float32 H x W x 4 (x 3 without "
        "alpha), 'metadata': {name: value} of its string attributes (a nimbus render's scene and "
        "settings)}.");
  m.def("write_image", &write_image_py, py::arg("path"), py::arg("pixels"), py::arg("exposure") = 0.0,
        "Writes an H x W x 3 or x 4 float array (linear; with alpha, premultiplied) as .exr (float) or .png "
        "(sRGB of the colour scaled by 2^exposure, over black), atomically.");
}

}  // namespace nimbus::python
