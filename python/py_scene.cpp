// Scenes from files and dicts (docs/python.md, "Scenes"): a dict goes through the same parser as a file
// (io/scene_json.cpp), so its errors are the file's messages with the JSON path; numpy volumes enter
// through the vdb shape's `volume` field.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>

#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "py_common.h"

namespace nimbus::python {

namespace {

// A name for `v` in the scene's volume table: its own name, made unique.
std::string volume_key(const Volume& v, const VolumeTable& volumes) {
  const std::string base = v.name.empty() ? "volume" : v.name;
  std::string key = base;
  for (int k = 2; volumes.count(key) && volumes.at(key) != v.grid; ++k) key = fmt::format("{}#{}", base, k);
  return key;
}

nlohmann::json to_json_at(py::handle obj, const std::string& where, const std::string& path,
                          VolumeTable* volumes) {
  auto fail = [&](const std::string& what) -> nlohmann::json {
    raise_scene_error(fmt::format("{}: {}: {}", where, path.empty() ? "/" : path, what));
  };
  if (obj.is_none()) return nullptr;
  if (PyBool_Check(obj.ptr())) return obj.cast<bool>();
  if (PyLong_Check(obj.ptr())) {
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(obj.ptr(), &overflow);
    if (overflow == 0) return int64_t(v);
    if (overflow > 0) {
      const unsigned long long u = PyLong_AsUnsignedLongLong(obj.ptr());
      if (!PyErr_Occurred()) return uint64_t(u);
      PyErr_Clear();
    }
    return fail("an integer out of the 64-bit range");
  }
  if (PyFloat_Check(obj.ptr())) return obj.cast<double>();
  if (py::isinstance<py::str>(obj)) return obj.cast<std::string>();
  if (py::isinstance<Volume>(obj)) {
    const Volume& v = obj.cast<const Volume&>();
    if (!volumes) fail("a nimbus.Volume belongs in a vdb shape's `volume` field of a scene dict");
    const std::string key = volume_key(v, *volumes);
    (*volumes)[key] = v.grid;
    return key;
  }
  if (py::isinstance<py::dict>(obj)) {
    nlohmann::json out = nlohmann::json::object();
    for (auto [k, value] : obj.cast<py::dict>()) {
      if (!py::isinstance<py::str>(k))
        fail(fmt::format("a key must be a string, not {}",
                         py::str(py::type::of(k).attr("__name__")).cast<std::string>()));
      const std::string key = k.cast<std::string>();
      out[key] = to_json_at(value, where, path + "/" + key, volumes);
    }
    return out;
  }
  if (py::isinstance<py::list>(obj) || py::isinstance<py::tuple>(obj)) {
    nlohmann::json out = nlohmann::json::array();
    size_t i = 0;
    for (py::handle item : obj)
      out.push_back(to_json_at(item, where, fmt::format("{}/{}", path, i++), volumes));
    return out;
  }
  // numpy arrays and scalars: as the Python lists and numbers they hold.
  if (py::isinstance<py::array>(obj) || py::hasattr(obj, "dtype")) {
    const py::object plain = py::isinstance<py::array>(obj) ? obj.attr("tolist")() : obj.attr("item")();
    return to_json_at(plain, where, path, volumes);
  }
  return fail(fmt::format("a {} has no JSON form (use dicts, lists, numbers, strings, booleans and None)",
                          py::str(py::type::of(obj).attr("__name__")).cast<std::string>()));
}

// Overrides as `render --set` takes them: a dict {"camera.width": 64, ...} or a list of "PATH=VALUE".
std::vector<std::string> override_list(const py::object& overrides) {
  std::vector<std::string> out;
  if (overrides.is_none()) return out;
  if (py::isinstance<py::dict>(overrides)) {
    for (auto [k, v] : overrides.cast<py::dict>()) {
      const std::string key = py::str(k).cast<std::string>();
      out.push_back(key + "=" + to_json_at(v, "overrides", "/" + key, nullptr).dump());
    }
    return out;
  }
  if (py::isinstance<py::str>(overrides))
    throw Error("overrides: a dict {\"camera.width\": 64} or a list of \"PATH=VALUE\" strings, not a string");
  for (py::handle item : overrides) out.push_back(py::str(item).cast<std::string>());
  return out;
}

template <typename F>
std::shared_ptr<Scene> scene_or_error(F&& f) {
  try {
    py::gil_scoped_release release;
    return std::make_shared<Scene>(f());
  } catch (const Error& e) {
    raise_scene_error(e.what());
  }
}

}  // namespace

nlohmann::json to_json(py::handle obj, const std::string& where, VolumeTable* volumes) {
  return to_json_at(obj, where, "", volumes);
}

py::object from_json(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

std::shared_ptr<Scene> scene_from_dict(const py::dict& doc, const py::object& base_dir,
                                       const py::object& overrides, const py::object& volumes,
                                       const std::string& name) {
  VolumeTable table;
  if (!volumes.is_none())
    for (auto [k, v] : volumes.cast<py::dict>()) {
      if (!py::isinstance<Volume>(v)) throw Error("volumes: the values must be nimbus.Volume objects");
      table[py::str(k).cast<std::string>()] = v.cast<const Volume&>().grid;
    }
  nlohmann::json j = to_json(doc, name, &table);
  const std::vector<std::string> sets = override_list(overrides);
  const std::filesystem::path base =
      base_dir.is_none() ? std::filesystem::current_path() : base_dir.cast<std::filesystem::path>();
  return scene_or_error([&] {
    for (const std::string& s : sets) apply_scene_override(j, s);
    return parse_scene(j, name, base, table);
  });
}

std::shared_ptr<Scene> as_scene(const py::object& scene) {
  if (py::isinstance<Scene>(scene)) return scene.cast<std::shared_ptr<Scene>>();
  if (py::isinstance<py::dict>(scene))
    return scene_from_dict(scene.cast<py::dict>(), py::none(), py::none(), py::none(), "(dict)");
  if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__")) {
    const auto path = scene.cast<std::filesystem::path>();
    return scene_or_error([&] { return load_scene(path); });
  }
  throw Error("scene: a nimbus.Scene, a dict or a path to a scene file");
}

void init_scene(py::module_& m) {
  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene",
                                            "A validated scene with its volumes loaded (load_scene, "
                                            "scene_from_dict); render it with nimbus.render.")
      .def_property_readonly(
          "width", [](const Scene& s) { return s.camera.width; }, "Image width [pixels]")
      .def_property_readonly(
          "height", [](const Scene& s) { return s.camera.height; }, "Image height [pixels]")
      .def_property_readonly("integrator", [](const Scene& s) { return s.integrator.type; })
      .def_property_readonly("spp", [](const Scene& s) { return s.integrator.spp; })
      .def_property_readonly("seed", [](const Scene& s) { return s.integrator.seed; })
      .def_property_readonly(
          "media", [](const Scene& s) { return s.media.size(); }, "Number of media")
      .def_property_readonly(
          "file",
          [](const Scene& s) -> py::object {
            if (s.file.empty()) return py::none();
            return py::str(s.file.string());
          },
          "The scene file (None for a dict)")
      .def_property_readonly(
          "document", [](const Scene& s) { return from_json(s.source); },
          "The scene's JSON document as a dict (overrides applied)")
      .def("__repr__", [](const Scene& s) {
        return fmt::format("<nimbus.Scene {}x{} {} spp {}, {} media, {} lights>", s.camera.width,
                           s.camera.height, s.integrator.type, s.integrator.spp, s.media.size(),
                           s.lights.size());
      });

  m.def(
      "load_scene",
      [](const std::filesystem::path& path, const py::object& overrides) {
        const std::vector<std::string> sets = override_list(overrides);
        return scene_or_error([&] { return load_scene(path, sets); });
      },
      py::arg("path"), py::arg("overrides") = py::none(),
      "Reads and validates a scene file (docs/scene-format.md), loading its volumes.\n\n"
      "overrides: a dict {'camera.width': 64, 'media.0.sigma_s': 2} or a list of 'PATH=VALUE' strings, "
      "applied as `nimbus render --set` applies them, before validation.\n"
      "Raises nimbus.SceneError naming the file and the JSON path of a bad field.");
  m.def("scene_from_dict", &scene_from_dict, py::arg("doc"), py::arg("base_dir") = py::none(),
        py::arg("overrides") = py::none(), py::arg("volumes") = py::none(), py::arg("name") = "(dict)",
        "A scene from a dict of the scene file's schema (docs/scene-format.md), validated by the same "
        "parser: errors raise nimbus.SceneError with the same messages, '(dict)' for the file.\n\n"
        "base_dir: where relative file paths resolve (default: the current directory).\n"
        "overrides: as load_scene's.\n"
        "volumes: {name: nimbus.Volume}, for vdb shapes that say {'type': 'vdb', 'volume': name}; a "
        "nimbus.Volume may also stand in the dict itself: {'type': 'vdb', 'volume': vol}.");
}

}  // namespace nimbus::python
