// nimbus.render (docs/python.md, "Rendering"): the render runs on its own thread with the GIL released;
// the calling thread waits for it, and every 50 ms takes the GIL to check for signals (Ctrl-C) and to
// hand the latest progress to the Python callback. A KeyboardInterrupt, or an exception raised by the
// callback, sets the render's cancel flag: the render stops within a tile and the exception propagates.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "nimbus/error.h"
#include "nimbus/render.h"
#include "py_common.h"

namespace nimbus::python {

namespace {

// What the render thread shares with the waiting one.
struct RenderRun {
  std::mutex mutex;
  std::condition_variable finished_cv;
  bool finished = false;
  std::atomic<bool> cancel{false};
  std::atomic<int64_t> done{-1}, total{0};
  RenderResult result;
  std::exception_ptr error;
};

// The layer a film channel belongs to: "Z" is depth, "direct.R" is direct.
std::string layer_of(const std::string& channel) {
  if (channel == "Z") return "depth";
  const size_t dot = channel.find('.');
  return dot == std::string::npos ? channel : channel.substr(0, dot);
}

// The image's RGBA (alpha 1 where the image has none) as H x W x 4.
py::array_t<float> rgba_array(const Image& img) {
  const size_t n = size_t(img.width) * img.height;
  std::vector<float> rgba(n * 4);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) rgba[i * 4 + c] = img.rgb[i * 3 + c];
    rgba[i * 4 + 3] = img.alpha.empty() ? 1.0f : img.alpha[i];
  }
  return float_array(rgba, {img.height, img.width, 4});
}

// The film's layers: one-channel layers as H x W, the others as H x W x C (channels in film order).
py::dict layer_arrays(const Image& img) {
  std::map<std::string, std::vector<const ImageChannel*>> layers;
  std::vector<std::string> order;
  for (const ImageChannel& c : img.channels) {
    const std::string name = layer_of(c.name);
    if (!layers.count(name)) order.push_back(name);
    layers[name].push_back(&c);
  }
  py::dict out;
  const size_t n = size_t(img.width) * img.height;
  for (const std::string& name : order) {
    const auto& channels = layers[name];
    const size_t k = channels.size();
    std::vector<float> data(n * k);
    for (size_t i = 0; i < n; ++i)
      for (size_t c = 0; c < k; ++c) data[i * k + c] = channels[c]->data[i];
    out[py::str(name)] = k == 1 ? float_array(data, {img.height, img.width})
                                : float_array(data, {img.height, img.width, py::ssize_t(k)});
  }
  return out;
}

// A transient render's bins (scene film.time_bins): "bins" N x H x W x 3 in time order, "under" and
// "over" H x W x 3 (path lengths before t0 and from t1 on), "edges" the N + 1 bin edges; together they
// sum to the steady image's RGB (docs/transient.md).
py::dict time_bins_dict(const Image& t, const TimeBins& tb) {
  const size_t n = size_t(t.width) * t.height, N = size_t(tb.count);
  std::vector<float> bins(N * n * 3, 0.0f), under(n * 3, 0.0f), over(n * 3, 0.0f);
  for (const ImageChannel& c : t.channels) {
    const std::string layer = layer_of(c.name);
    const char ch = c.name.back();
    const int ci = ch == 'R' ? 0 : ch == 'G' ? 1 : ch == 'B' ? 2 : -1;
    if (ci < 0 || c.name.size() != layer.size() + 2) continue;
    float* dst = nullptr;
    if (layer == "time_under") {
      dst = under.data();
    } else if (layer == "time_over") {
      dst = over.data();
    } else if (layer.size() > 4 && layer.rfind("time", 0) == 0 &&
               layer.find_first_not_of("0123456789", 4) == std::string::npos) {
      const size_t k = std::stoul(layer.substr(4));
      if (k < N) dst = &bins[k * n * 3];
    }
    if (!dst) continue;
    for (size_t i = 0; i < n; ++i) dst[i * 3 + ci] = c.data[i];
  }
  std::vector<double> edges(N + 1);
  for (size_t k = 0; k <= N; ++k) edges[k] = tb.t0 + (tb.t1 - tb.t0) * double(k) / double(N);
  py::dict d;
  d["bins"] = float_array(bins, {py::ssize_t(N), t.height, t.width, 3});
  d["under"] = float_array(under, {t.height, t.width, 3});
  d["over"] = float_array(over, {t.height, t.width, 3});
  d["edges"] = py::array_t<double>(py::ssize_t(edges.size()), edges.data());
  return d;
}

py::dict result_dict(const RenderResult& r, const Scene& scene) {
  py::dict d;
  d["rgba"] = rgba_array(r.image);
  d["layers"] = layer_arrays(r.image);
  d["width"] = r.image.width;
  d["height"] = r.image.height;
  d["integrator"] = r.integrator;
  d["spp"] = r.spp;
  d["spp_requested"] = r.spp_requested;
  d["seed"] = r.seed;
  d["seconds"] = r.seconds;
  d["time_limited"] = r.time_limited;
  d["nonfinite_samples"] = r.nonfinite_samples;
  d["spp_mean"] = r.spp_mean;
  d["noise_estimate"] = r.noise_estimate;
  d["settings"] = from_json(r.settings);
  py::dict meta;
  for (const auto& [k, v] : r.metadata) meta[py::str(k)] = v;
  d["metadata"] = meta;
  if (scene.film.time_bins && r.transient.width > 0)
    d["time_bins"] = time_bins_dict(r.transient, *scene.film.time_bins);
  return d;
}

// Waits for the render thread; with the GIL every 50 ms: signals, then the progress callback. Returns the
// Python exception that stopped the render, if any (the render is then cancelled and awaited).
std::optional<py::error_already_set> wait_for_render(RenderRun& run, const py::object& progress) {
  std::optional<py::error_already_set> raised;
  int64_t reported = -1;
  for (bool finished = false; !finished;) {
    {
      py::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(run.mutex);
      finished = run.finished_cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return run.finished; });
    }
    if (raised) continue;  // cancelled: wait for the render to drop its pass
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      const int64_t done = run.done.load();
      if (!progress.is_none() && done > reported && (done >= 0 || finished)) {
        reported = done;
        progress(done, run.total.load());
      }
    } catch (py::error_already_set& e) {
      raised.emplace(std::move(e));
      run.cancel.store(true);
    }
  }
  return raised;
}

py::dict render_py(const py::object& scene_obj, std::optional<int> spp, int threads,
                   std::optional<std::string> integrator, std::optional<uint64_t> seed,
                   std::optional<std::vector<std::string>> layers, const py::object& progress,
                   std::optional<double> time_limit, std::optional<double> noise, int noise_bin) {
  const std::shared_ptr<Scene> scene = as_scene(scene_obj);
  RenderRun run;
  RenderOptions options;
  options.spp = spp;
  options.seed = seed;
  options.integrator = integrator;
  options.layers = layers;
  options.threads = threads;
  options.time_limit = time_limit.value_or(0.0);
  options.noise = noise.value_or(0.0);
  options.noise_bin = noise_bin;
  if (options.noise > 0.0 && !spp) options.spp = kAdaptiveDefaultMaxSpp;  // as render --noise
  options.cancel = &run.cancel;
  // Called from worker threads, possibly out of order: keep the largest count.
  options.progress = [&run](int64_t done, int64_t total, int64_t) {
    run.total.store(total);
    int64_t seen = run.done.load();
    while (done > seen && !run.done.compare_exchange_weak(seen, done)) {
    }
  };
  std::thread worker([&run, &options, scene] {
    try {
      run.result = render(*scene, options);
    } catch (...) {
      run.error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(run.mutex);
    run.finished = true;
    run.finished_cv.notify_all();
  });
  std::optional<py::error_already_set> raised;
  try {
    raised = wait_for_render(run, progress);
  } catch (...) {
    run.cancel.store(true);
    py::gil_scoped_release release;
    worker.join();
    throw;
  }
  {
    py::gil_scoped_release release;
    worker.join();
  }
  if (raised) throw std::move(*raised);
  if (run.error) std::rethrow_exception(run.error);
  if (run.result.partial) throw Cancelled();
  return result_dict(run.result, *scene);
}

}  // namespace

void init_render(py::module_& m) {
  m.def("render", &render_py, py::arg("scene"), py::arg("spp") = py::none(), py::arg("threads") = 0,
        py::arg("integrator") = py::none(), py::arg("seed") = py::none(), py::arg("layers") = py::none(),
        py::arg("progress") = py::none(), py::arg("time_limit") = py::none(), py::arg("noise") = py::none(),
        py::arg("noise_bin") = 4,
        R"(Renders a scene: a nimbus.Scene, a dict (scene_from_dict) or a path (load_scene).

spp, integrator, seed: override the scene's integrator block (another integrator than the scene's
  starts from its own defaults, as `nimbus render --integrator` does).
threads: worker threads, 0 = all cores (the image is the same for any count).
layers: compositing layers to keep besides RGBA, e.g. ['depth', 'direct'] (names: nimbus.layer_names()).
progress: called as progress(done, total) with the samples taken and to take (over all pixels), from the calling
  thread, at most every 50 ms and once at the end.
time_limit: a budget in seconds; the render takes whole passes (1, 2, 4, ... spp) while they fit.
noise: adaptive sampling, as `nimbus render --noise`: passes until the estimated binned relative RMSE
  (noise_bin x noise_bin bins, bins darker than 5 % of the mean left out) is at most this; spp is then the
  most samples a pixel may take (default 4096).

The GIL is released while rendering. Ctrl-C (KeyboardInterrupt), or an exception raised by the
progress callback, stops the render within a tile and propagates.

Returns a dict: 'rgba' float32 H x W x 4 (linear, premultiplied alpha, row 0 the top), 'layers'
{name: float32 H x W (depth [world units], samples) or H x W x 3}, and the resolved settings:
'width', 'height', 'integrator', 'spp' (reached), 'spp_requested', 'seed', 'seconds' (wall time),
'time_limited', 'nonfinite_samples', 'spp_mean', 'noise_estimate' (adaptive sampling), 'settings' (the integrator block as rendered, auto choices
resolved), 'metadata' (what an EXR header would carry). A transient render (the scene's
film.time_bins, pathtrace only) adds 'time_bins': {'bins' float32 N x H x W x 3 in time order, 'under' and
'over' H x W x 3 (path lengths before t0, from t1 on), 'edges' the N + 1 edges}; bins, under and over sum
to the RGB (docs/transient.md).)");
  m.def("integrator_names", &integrator_names, "Names of the integrators.");
  m.def("layer_names", &film_layer_names, "Names of the compositing layers a render can keep.");
}

}  // namespace nimbus::python
