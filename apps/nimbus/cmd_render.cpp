// nimbus render [SCENE.json] -o OUT.exr|OUT.png: renders a scene (the built-in demo without one).
#include <fmt/format.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.h"
#include "frames.h"
#include "nimbus/error.h"
#include "nimbus/image.h"
#include "nimbus/render.h"
#include "nimbus/scene.h"
#include "progress.h"
#include "ranges.h"

namespace nimbus::cli {

namespace {

std::atomic<bool> g_cancel{false};
std::atomic<int> g_signal{0};

extern "C" void on_signal(int sig) {
  g_signal.store(sig);
  g_cancel.store(true);
}

struct RenderArgs {
  std::string scene;
  std::string output;
  std::string preview;  // optional PNG written beside the main output
  std::optional<int> spp;
  std::optional<uint64_t> seed;
  std::optional<std::string> integrator;
  std::vector<std::string> layers;  // --layers: replaces the scene's film.layers
  bool layers_given = false;
  std::string deep;  // --deep: a deep EXR of the media beside the main output
  int deep_samples = 32;
  int threads = 0;
  double exposure = 0.0;
  double time_limit = 0.0;               // --time: seconds, 0 = none
  std::string resume;                    // --resume: the EXR to continue
  std::vector<std::string> sets;         // --set PATH=VALUE
  std::string res;                       // --res WxH
  std::string region;                    // --region x0,y0,x1,y1
  std::string samples;                   // --samples START:COUNT
  std::optional<std::string> frames;     // --frames LIST: a sequence, $F / $F4 in file names
  std::optional<int> frame;              // the frame this run renders (one of --frames)
  double noise = 0.0;                    // --noise: adaptive sampling to this binned relative RMSE
  int noise_bin = 4;                     // --noise-bin
  std::optional<std::string> time_bins;  // --time-bins T0,T1,N: film.time_bins (a transient render)
  bool quiet = false;
};

std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// The name a partial (interrupted) image is written under: OUT.partial.EXT, so that an existing
// complete output is never replaced by an interrupted run.
std::filesystem::path partial_name(const std::filesystem::path& out) {
  if (out.stem().extension() == ".partial") return out;  // resuming a partial image: it grows in place
  std::filesystem::path p = out;
  p.replace_extension(".partial" + out.extension().string());
  return p;
}

void check_output_names(const RenderArgs& args) {
  check_output_path(args.output, "--output");
  if (!args.preview.empty()) check_output_path(args.preview, "--preview");
  if (!args.deep.empty()) check_output_path(args.deep, "--deep");
  const std::filesystem::path out(args.output);
  const std::string ext = lower_extension(out);
  if (ext != ".exr" && ext != ".png")
    throw Error(fmt::format("{}: unsupported output format '{}' (use .exr or .png)", args.output, ext));
  if (!args.preview.empty() && lower_extension(args.preview) != ".png")
    throw Error(fmt::format("{}: the preview must be a .png file", args.preview));
  if (args.layers_given && ext != ".exr")
    throw Error(fmt::format("--layers: {}: layers need an .exr output", args.output));
  if (!args.deep.empty() && lower_extension(args.deep) != ".exr")
    throw Error(fmt::format("--deep: {}: the deep image must be an .exr file", args.deep));
}

std::string meta_value(const ImageMetadata& meta, const std::string& key, const std::string& file) {
  for (const auto& [k, v] : meta)
    if (k == key) return v;
  throw Error(fmt::format("{}: no {} in the header (not a nimbus render?)", file, key));
}

// The region and sample range a resumed render had (absent in files from before them: none).
void resume_window(const ImageMetadata& meta, const std::string& file, RenderOptions* options) {
  for (const auto& [k, v] : meta) {
    if (k == "nimbus/region") options->region = parse_region(v, file + ": nimbus/region");
    if (k == "nimbus/sample_start") {
      char extra = 0;
      if (std::sscanf(v.c_str(), "%d%c", &options->sample_start, &extra) != 1 || options->sample_start < 0)
        throw Error(fmt::format("{}: nimbus/sample_start '{}' is not a sample index", file, v));
    }
  }
}

// --resume FILE: the scene, spp and film state of a nimbus EXR. The render goes on to args.spp, or to
// the spp the file asked for.
Scene resume_scene(const RenderArgs& args, FilmState* state, RenderOptions* options) {
  std::optional<int>* spp = &options->spp;
  if (!args.scene.empty())
    throw Error(
        fmt::format("--resume: {}: the scene comes from the EXR's header; give no scene file", args.scene));
  if (args.integrator || args.seed || args.layers_given || !args.deep.empty() || !args.sets.empty() ||
      !args.res.empty() || !args.region.empty() || !args.samples.empty() || args.time_bins)
    throw Error(
        "--resume: --integrator, --seed, --layers, --deep, --set, --res, --region, --samples and --time-bins "
        "must be those of the resumed render");
  ImageMetadata meta;
  read_exr(args.resume, &meta);
  *state = read_exr_state(args.resume);
  const std::filesystem::path file(meta_value(meta, "nimbus/scene_file", args.resume));
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(meta_value(meta, "nimbus/scene", args.resume));
  } catch (const nlohmann::json::exception&) {
    throw Error(fmt::format("{}: nimbus/scene: not valid JSON", args.resume));
  }
  Scene scene = parse_scene(doc, args.resume + " (nimbus/scene)", file.parent_path());
  scene.file = file;
  resume_window(meta, args.resume, options);
  const int requested = scene.integrator.spp;
  *spp = args.spp ? *args.spp : requested;
  if (**spp <= state->spp && args.noise <= 0.0)
    throw Error(
        fmt::format("--resume: {} has {} spp already; ask for more with --spp", args.resume, state->spp));
  return scene;
}

// A transient render's time bins go beside the image: OUT.time.exr (docs/transient.md).
std::filesystem::path transient_name(const std::filesystem::path& out) {
  std::filesystem::path p = out;
  return p.replace_extension(".time.exr");
}

// Writes the image (with its film state in an EXR), the preview and the deep image under `out`.
void write_outputs(const RenderArgs& args, const RenderResult& r, const std::filesystem::path& out,
                   const std::function<std::filesystem::path(const std::string&)>& name) {
  const FilmState* state = r.state.layers.empty() ? nullptr : &r.state;
  write_image(out, r.image, r.metadata, args.exposure, false, state);
  if (!args.preview.empty()) write_image(name(args.preview), r.image, {}, args.exposure);
  if (!args.deep.empty() && !r.deep.offsets.empty()) write_deep_exr(name(args.deep), r.deep, r.metadata);
  if (!r.transient.rgb.empty()) write_exr(transient_name(out), r.transient, r.metadata);
}

// --res WxH as two --set overrides.
std::vector<std::string> scene_overrides(const RenderArgs& args) {
  std::vector<std::string> sets = args.sets;
  if (!args.res.empty()) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(args.res.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') ||
        w < 1 || h < 1)
      throw Error(fmt::format("--res '{}': expected WIDTHxHEIGHT, e.g. 1920x1080", args.res));
    sets.push_back(fmt::format("camera.width={}", w));
    sets.push_back(fmt::format("camera.height={}", h));
  }
  if (args.time_bins) sets.push_back("film.time_bins=[" + *args.time_bins + "]");
  return sets;
}

// --integrator NAME naming another integrator than the document's: its block becomes NAME's defaults
// (keeping spp, seed and max_events, which every integrator has), as the library's switch would make
// it, but before the --set overrides, so that `--integrator mfs --set integrator.photons=...` sets
// mfs's field instead of being checked against the scene's integrator.
void switch_integrator(nlohmann::json& doc, const std::string& name) {
  if (!doc.is_object()) return;  // the parser names what is wrong with the document
  const nlohmann::json old = doc.contains("integrator") ? doc["integrator"] : nlohmann::json::object();
  if (!old.is_object() || (old.contains("type") && !old["type"].is_string())) return;  // likewise
  if (old.value("type", IntegratorSettings().type) == name) return;
  nlohmann::json block = {{"type", name}};
  for (const char* key : {"spp", "seed", "max_events"})
    if (old.contains(key)) block[key] = old[key];
  doc["integrator"] = std::move(block);
}

Scene load_render_scene(const RenderArgs& args) {
  const std::vector<std::string> sets = scene_overrides(args);
  if (!args.frame && !args.integrator) {
    if (!args.scene.empty()) return load_scene(args.scene, sets);
    if (sets.empty()) return builtin_demo_scene();
  }
  // The document, the integrator switch, its overrides, then (a frame of a sequence) $F in every
  // string: file names and all.
  nlohmann::json doc = args.scene.empty() ? builtin_demo_document() : read_scene_document(args.scene);
  if (args.integrator) switch_integrator(doc, *args.integrator);
  for (const std::string& o : sets) apply_scene_override(doc, o);
  if (args.frame) substitute_frame(doc, *args.frame);
  if (args.scene.empty()) return parse_scene(doc, "(built-in demo)", ".");
  Scene scene = parse_scene(doc, args.scene, std::filesystem::path(args.scene).parent_path());
  scene.file = args.scene;
  return scene;
}

// --region against the scene's image size (the library checks again, without the option's name).
void check_region(const RenderArgs& args, const Scene& scene, const RenderOptions& options) {
  const Region& r = *options.region;
  const int w = scene.camera.width, h = scene.camera.height;
  if (!(0 <= r.x0 && r.x0 < r.x1 && r.x1 <= w && 0 <= r.y0 && r.y0 < r.y1 && r.y1 <= h))
    throw Error(fmt::format(
        "--region {}: not a window inside the {}x{} image (x0,y0,x1,y1 in pixels, half-open: 0 <= x0 < "
        "x1 <= {}, 0 <= y0 < y1 <= {})",
        args.region, w, h, w, h));
}

int run_render(RenderArgs args);

// --frames: the frames one after another, $F in the scene's strings and the output names. Stops at the
// first frame that fails (a bad scene exits 2 naming it, an interrupted frame 1).
int run_frames(const RenderArgs& args) {
  const std::vector<int> frames = parse_frames(*args.frames);
  if (!args.resume.empty()) throw Error("--frames: not with --resume (resume each frame's file)");
  if (!has_frame_token(args.output))
    throw Error(fmt::format(
        "--frames: the output '{}' holds no frame number: write $F or $F4 in it (e.g. -o out/cloud.$F4.exr)",
        args.output));
  for (const std::string* name : {&args.preview, &args.deep})
    if (!name->empty() && !has_frame_token(*name))
      throw Error(fmt::format("--frames: '{}' holds no frame number ($F or $F4)", *name));
  auto frame_args = [&](int f) {
    RenderArgs a = args;
    a.frames.reset();
    a.frame = f;
    a.output = substitute_frame(args.output, f);
    a.preview = substitute_frame(args.preview, f);
    a.deep = substitute_frame(args.deep, f);
    return a;
  };
  for (const int f : frames) check_output_names(frame_args(f));  // every frame's names, before any work
  for (const int f : frames)
    if (const int rc = run_render(frame_args(f)); rc != kExitOk) return rc;
  return kExitOk;
}

int run_render(RenderArgs args) {
  if (args.frames) return run_frames(args);
  if (!args.resume.empty() && args.output.empty()) args.output = args.resume;
  if (args.output.empty()) throw Error("--output is required");
  check_output_names(args);
  const std::filesystem::path out(args.output);
  RenderOptions options;
  FilmState state;
  std::optional<Scene> resumed;
  if (!args.resume.empty()) {
    resumed.emplace(resume_scene(args, &state, &options));
    options.resume = &state;
  } else {
    options.spp = args.spp;
    if (args.noise > 0.0 && !args.spp) options.spp = kAdaptiveDefaultMaxSpp;
    if (!args.region.empty()) options.region = parse_region(args.region, "--region");
    if (!args.samples.empty()) {
      if (args.spp) throw Error("--samples START:COUNT sets the spp (COUNT): give no --spp");
      const auto [start, count] = parse_samples(args.samples);
      options.sample_start = start;
      options.spp = count;
    }
    if ((options.region || options.sample_start > 0) && !args.deep.empty())
      throw Error(
          "--deep: a deep image is made of the whole image and all its samples (no --region, --samples)");
  }
  options.noise = args.noise;
  options.noise_bin = args.noise_bin;
  const Scene scene = resumed ? std::move(*resumed) : load_render_scene(args);
  if (options.region && args.resume.empty()) check_region(args, scene, options);
  options.seed = args.seed;
  options.integrator = args.integrator;
  if (args.layers_given) options.layers = args.layers;
  if (!args.deep.empty()) options.deep_samples = args.deep_samples;
  options.threads = args.threads;
  options.time_limit = args.time_limit;
  options.cancel = &g_cancel;
  std::string label = !args.resume.empty() ? args.resume : args.scene.empty() ? "demo" : args.scene;
  if (args.frame) label += fmt::format(" frame {}", *args.frame);
  ProgressBar bar(fmt::format("nimbus: {}", label), !args.quiet && stderr_is_terminal());
  options.setup = [&bar](const std::string& what) { bar.stage(what); };
  options.progress = [&bar](int64_t done, int64_t total, int64_t samples) {
    bar.update(done, total, samples);
  };

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  RenderResult result = render(scene, options);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  bar.finish();
  if (args.frame) result.metadata.emplace_back("nimbus/frame", std::to_string(*args.frame));

  if (result.nonfinite_samples > 0)
    fmt::print(stderr, "nimbus: warning: {} non-finite or out-of-range samples were dropped\n",
               result.nonfinite_samples);
  const char* signal = g_signal.load() == SIGTERM ? "SIGTERM" : "SIGINT";
  if (result.partial && result.spp == 0) {
    fmt::print(stderr, "nimbus: interrupted ({}) before the first pass ended: nothing written\n", signal);
    return kExitFailure;
  }
  if (result.partial) {
    const auto target = partial_name(out);
    write_outputs(args, result, target, [](const std::string& p) { return partial_name(p); });
    fmt::print(stderr,
               "nimbus: interrupted ({}) at {} of {} spp: image written to {} (continue it with "
               "`nimbus render --resume {} -o {}`)\n",
               signal, result.spp, result.spp_requested, target.string(), target.string(), out.string());
    return kExitFailure;
  }
  write_outputs(args, result, out, [](const std::string& p) { return std::filesystem::path(p); });
  if (result.time_limited)
    fmt::print(stderr, "nimbus: time limit of {} s reached at {} of {} spp\n", args.time_limit, result.spp,
               result.spp_requested);
  if (!args.quiet && result.noise_target > 0.0) {
    fmt::print(stderr,
               "nimbus: {} {}x{} adaptive: {:.1f} spp on average (at most {}), estimated noise {:.2f} % "
               "(target {:.2f} %) in {:.2f}s -> {}\n",
               result.integrator, result.image.width, result.image.height, result.spp_mean, result.spp,
               100.0 * result.noise_estimate, 100.0 * result.noise_target, result.seconds, out.string());
  } else if (!args.quiet) {
    fmt::print(stderr, "nimbus: {} {}x{} {} spp in {:.2f}s -> {}\n", result.integrator, result.image.width,
               result.image.height, result.spp, result.seconds, out.string());
  }
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "Render a scene file (or the built-in demo) to EXR or PNG");
  cmd->add_option("scene", args->scene, "Scene JSON file (omit for the built-in demo)");
  cmd->add_option("-o,--output", args->output,
                  "Output image: .exr (linear float premultiplied RGBA and layers) or .png (sRGB preview); "
                  "with --resume, the resumed file by default");
  cmd->add_option("--preview", args->preview, "Also write an sRGB PNG preview of the same render");
  cmd->add_option("--spp", args->spp, "Samples per pixel (overrides the scene)")
      ->check(CLI::Range(1, kMaxSpp));
  cmd->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 4096));
  cmd->add_option("--seed", args->seed, "Random seed (overrides the scene)");
  std::string names;
  for (const std::string& n : integrator_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--integrator", args->integrator, "Integrator (overrides the scene): " + names)
      ->check(CLI::IsMember(integrator_names()));
  cmd->add_option("--layers", args->layers,
                  "Compositing layers for the EXR, comma-separated (replaces the scene's film.layers): " +
                      fmt::format("{}", fmt::join(film_layer_names(), ", ")))
      ->delimiter(',')
      ->check(CLI::IsMember(film_layer_names()))
      ->each([args](const std::string&) { args->layers_given = true; });
  auto* deep = cmd->add_option("--deep", args->deep,
                               "Also write a deep EXR of the media (Z, ZBack, premultiplied RGBA)");
  cmd->add_option("--deep-samples", args->deep_samples, "Most deep samples per pixel (default 32)")
      ->check(CLI::Range(1, kMaxDeepSamples))
      ->needs(deep);
  cmd->add_option("--time-bins", args->time_bins,
                  "A transient render (pathtrace): also write OUT.time.exr with the light binned by path "
                  "length from the light, N bins over [T0, T1) (sets film.time_bins)")
      ->type_name("T0,T1,N");
  cmd->add_option("--exposure", args->exposure, "Exposure in stops for PNG output")
      ->check(CLI::Range(-64.0, 64.0));
  cmd->add_option("--set", args->sets,
                  "Override a scene field, validated as if in the file: PATH=VALUE with PATH like "
                  "camera.width or media.0.sigma_s, VALUE JSON (2, [1,0,0], true) or a string; repeatable")
      ->allow_extra_args(false)
      ->take_all();
  cmd->add_option("--noise", args->noise,
                  "Adaptive sampling: render until the estimated binned relative RMSE (as nimbus compare "
                  "--bin K --min-ref 0.05 against a noise-free image) is at most this, e.g. 0.02; --spp is "
                  "then the most samples a pixel may take (default 4096)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--noise-bin", args->noise_bin, "The bin size K of --noise (default 4)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--res", args->res, "Image size WIDTHxHEIGHT (sets camera.width and camera.height)");
  cmd->add_option("--time", args->time_limit,
                  "Time budget in seconds, set-up included: whole passes (1, 2, 4, ... spp) while they fit")
      ->check(CLI::Range(0.0, 1e8));
  cmd->add_option("--resume", args->resume,
                  "Continue this EXR (a partial or finished nimbus render) to more samples (--spp, default "
                  "the spp it asked for); the scene comes from its header. Bit-identical to one render");
  cmd->add_option("--region", args->region,
                  "Render only the crop window x0,y0,x1,y1 (pixels of the full image, row 0 at the top, "
                  "half-open: x0 <= x < x1); the EXR keeps the full display window, the crop as data window");
  cmd->add_option("--samples", args->samples,
                  "Take sample indices START..START+COUNT-1 of every pixel (START:COUNT, instead of --spp): "
                  "renders of disjoint ranges combine with `nimbus merge`");
  cmd->add_option("--frames", args->frames,
                  "Render a sequence, frame by frame: LIST like 1-240, 1-10x2 (every 2nd), 1,3,5 or 1-4,10; "
                  "$F (the frame) and $F4 (zero-padded to 4 digits) are replaced in every string of the "
                  "scene (volume and mesh files...), in --set values and in -o, --preview, --deep");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar or summary");
  cmd->callback([args, &action] { action = [args] { return run_render(*args); }; });
}

}  // namespace nimbus::cli
