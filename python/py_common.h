// Shared by the Python module's files (docs/python.md): the exception types, the conversions between
// Python objects and JSON, numpy arrays from C++ buffers, and the in-memory volume type.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/scene_volumes.h"
#include "nimbus/scene.h"

namespace nimbus::python {

namespace py = pybind11;

// nimbus.Error (a ValueError: bad input of any kind) and nimbus.SceneError (a scene that does not
// validate; its message carries the file or "(dict)" and the JSON path, e.g. "/media/0/sigma_s").
PyObject* error_type();
PyObject* scene_error_type();
// Raises nimbus.SceneError with `message` (throws py::error_already_set).
[[noreturn]] void raise_scene_error(const std::string& message);

// A density grid made from a numpy array (py_volume.cpp), or read from a file: what a scene's vdb shape
// takes through its `volume` field.
struct Volume {
  std::shared_ptr<const DensityGrid> grid;
  std::shared_ptr<void> openvdb_grid;  // the openvdb::FloatGrid it was built from (numpy volumes), for save()
  std::string name;
};

// A Python object (dict, list, tuple, str, int, float, bool, None, numpy scalars and arrays) as JSON.
// A nimbus.Volume met on the way is added to `volumes` under a generated name, written in its place.
// Errors: nimbus.SceneError naming `where` and the JSON path of the object that has no JSON form.
nlohmann::json to_json(py::handle obj, const std::string& where, VolumeTable* volumes);
// JSON as Python objects (through the json module: dicts, lists, str, int, float, bool, None).
py::object from_json(const nlohmann::json& j);

// A float32 numpy array of the given shape that owns a copy of `data` (data.size() = product of shape).
py::array_t<float> float_array(const std::vector<float>& data, const std::vector<py::ssize_t>& shape);
py::array_t<double> double_array(const std::vector<double>& data, const std::vector<py::ssize_t>& shape);

// A nimbus.Scene as it is; a dict through scene_from_dict (default arguments); a path through load_scene.
std::shared_ptr<Scene> as_scene(const py::object& scene);

void init_scene(py::module_& m);
void init_render(py::module_& m);
void init_volume(py::module_& m);
void init_transport(py::module_& m);
void init_image(py::module_& m);

}  // namespace nimbus::python
