// nimbus render [SCENE.json] -o OUT.exr|OUT.png: renders a scene (the built-in demo without one).
#include <fmt/format.h>

#include <csignal>
#include <filesystem>
#include <optional>

#include "commands.h"
#include "nimbus/error.h"
#include "nimbus/image.h"
#include "nimbus/render.h"
#include "nimbus/scene.h"
#include "progress.h"

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
  std::filesystem::path p = out;
  p.replace_extension(".partial" + out.extension().string());
  return p;
}

int run_render(const RenderArgs& args) {
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
  const std::filesystem::path dir = out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw Error(fmt::format("{}: output directory '{}' does not exist", args.output, dir.string()));

  const Scene scene = args.scene.empty() ? builtin_demo_scene() : load_scene(args.scene);

  RenderOptions options;
  options.spp = args.spp;
  options.seed = args.seed;
  options.integrator = args.integrator;
  if (args.layers_given) options.layers = args.layers;
  if (!args.deep.empty()) options.deep_samples = args.deep_samples;
  options.threads = args.threads;
  options.cancel = &g_cancel;
  ProgressBar bar(fmt::format("nimbus: {}", args.scene.empty() ? "demo" : args.scene),
                  !args.quiet && stderr_is_terminal());
  options.progress = [&bar](int64_t done, int64_t total, int64_t samples) {
    bar.update(done, total, samples);
  };

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  RenderResult result = render(scene, options);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  bar.finish();

  if (result.nonfinite_samples > 0)
    fmt::print(stderr, "nimbus: warning: {} non-finite samples were dropped\n", result.nonfinite_samples);
  if (result.partial) {
    const auto target = partial_name(out);
    write_image(target, result.image, result.metadata, args.exposure);
    if (!args.preview.empty()) write_image(partial_name(args.preview), result.image, {}, args.exposure);
    if (!args.deep.empty()) write_deep_exr(partial_name(args.deep), result.deep, result.metadata);
    fmt::print(stderr, "nimbus: interrupted ({}): partial image ({} of {} tiles) written to {}\n",
               g_signal.load() == SIGTERM ? "SIGTERM" : "SIGINT", result.tiles_done, result.tiles_total,
               target.string());
    return kExitFailure;
  }
  write_image(out, result.image, result.metadata, args.exposure);
  if (!args.preview.empty()) write_image(args.preview, result.image, {}, args.exposure);
  if (!args.deep.empty()) write_deep_exr(args.deep, result.deep, result.metadata);
  if (!args.quiet) {
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
                  "Output image: .exr (linear float premultiplied RGBA and layers) or .png (sRGB preview)")
      ->required();
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
  cmd->add_option("--exposure", args->exposure, "Exposure in stops for PNG output")
      ->check(CLI::Range(-64.0, 64.0));
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar or summary");
  cmd->callback([args, &action] { action = [args] { return run_render(*args); }; });
}

}  // namespace nimbus::cli
