// The Python module `nimbus` (docs/python.md): scenes from files or dicts, renders to numpy arrays, numpy
// volumes, and the beam and slab transport tools. Each part registers itself from its own file.
#include <exception>

#include "nimbus/error.h"
#include "py_common.h"

namespace nimbus::python {

namespace {
// Owned by the module for the life of the process (never freed: the interpreter may outlive statics).
PyObject* g_error = nullptr;
PyObject* g_scene_error = nullptr;
}  // namespace

PyObject* error_type() { return g_error; }
PyObject* scene_error_type() { return g_scene_error; }

void raise_scene_error(const std::string& message) {
  PyErr_SetString(g_scene_error, message.c_str());
  throw py::error_already_set();
}

}  // namespace nimbus::python

PYBIND11_MODULE(nimbus, m) {
  namespace py = pybind11;
  using namespace nimbus::python;
  m.doc() =
      "nimbus: a renderer of participating media (clouds, smoke) with an unbiased path tracer and fast "
      "approximations.\n\n"
      "  scene = nimbus.load_scene('cloud.json')          # or nimbus.scene_from_dict({...})\n"
      "  result = nimbus.render(scene, spp=64)             # result['rgba']: float32 H x W x 4\n\n"
      "Errors in the input raise nimbus.Error (a ValueError); scenes that do not validate raise "
      "nimbus.SceneError with the JSON path of the field. docs/python.md describes the whole module.";
  g_error = PyErr_NewExceptionWithDoc("nimbus.Error", "Bad input to nimbus (a file, a field, an argument).",
                                      PyExc_ValueError, nullptr);
  g_scene_error = PyErr_NewExceptionWithDoc(
      "nimbus.SceneError",
      "A scene that does not validate; the message names the file (or '(dict)') and the JSON path.", g_error,
      nullptr);
  m.attr("Error") = py::handle(g_error);
  m.attr("SceneError") = py::handle(g_scene_error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const nimbus::Cancelled& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const nimbus::Error& e) {
      PyErr_SetString(g_error, e.what());
    }
  });
  init_image(m);
  init_volume(m);
  init_scene(m);
  init_render(m);
  init_transport(m);
}
