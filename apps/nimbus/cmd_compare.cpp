// nimbus compare A.exr B.exr: error metrics of A against the reference B.
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "heatmap_legend.h"
#include "nimbus/compare.h"
#include "nimbus/image.h"

namespace nimbus::cli {

namespace {

struct CompareArgs {
  std::string a, b, heatmap;
  int bin = 1;
  double min_ref = 0.0, heatmap_range = 0.5;
  bool json = false;
};

int run_compare(const CompareArgs& args) {
  const Image a = read_exr(args.a), b = read_exr(args.b);
  CompareOptions o;
  o.bin = args.bin;
  o.min_reference = args.min_ref;
  const CompareResult r = compare_images(a, b, o);
  if (!args.heatmap.empty())
    write_image(args.heatmap,
                with_heatmap_legend(error_heatmap(a, b, o, args.heatmap_range), args.heatmap_range), {}, 0.0);
  if (args.json) {
    const nlohmann::json j = {{"a", args.a},
                              {"b", args.b},
                              {"bin", args.bin},
                              {"mean_a", {r.mean_a[0], r.mean_a[1], r.mean_a[2]}},
                              {"mean_b", {r.mean_b[0], r.mean_b[1], r.mean_b[2]}},
                              {"mean_luminance_a", r.mean_lum_a},
                              {"mean_luminance_b", r.mean_lum_b},
                              {"mean_rel_error", r.mean_rel_error},
                              {"rel_rmse", r.rel_rmse},
                              {"mean_abs_rel_error", r.mean_abs_rel_error},
                              {"max_abs_rel_error", r.max_abs_rel_error},
                              {"bins_used", r.bins_used},
                              {"bins_total", r.bins_total}};
    fmt::print("{}\n", j.dump(2));
    return kExitOk;
  }
  fmt::print("A (test)      {}: mean RGB [{:.6g}, {:.6g}, {:.6g}], luminance {:.6g}\n", args.a, r.mean_a[0],
             r.mean_a[1], r.mean_a[2], r.mean_lum_a);
  fmt::print("B (reference) {}: mean RGB [{:.6g}, {:.6g}, {:.6g}], luminance {:.6g}\n", args.b, r.mean_b[0],
             r.mean_b[1], r.mean_b[2], r.mean_lum_b);
  fmt::print("whole-image mean error      {:+.4f} %\n", 100.0 * r.mean_rel_error);
  fmt::print("relative RMSE ({}x{} bins)   {:.4f} %\n", args.bin, args.bin, 100.0 * r.rel_rmse);
  fmt::print("mean |relative error|       {:.4f} %\n", 100.0 * r.mean_abs_rel_error);
  fmt::print("bins used                   {} of {}\n", r.bins_used, r.bins_total);
  return kExitOk;
}

}  // namespace

void add_compare_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<CompareArgs>();
  auto* cmd = app.add_subcommand("compare", "Compare an EXR image against a reference EXR");
  cmd->add_option("a", args->a, "Test image (EXR)")->required();
  cmd->add_option("b", args->b, "Reference image (EXR)")->required();
  cmd->add_option("--bin", args->bin, "Bin k x k pixels before the per-bin metrics")
      ->check(CLI::Range(1, 1 << 16));
  cmd->add_option("--min-ref", args->min_ref,
                  "Exclude bins whose reference luminance is below this fraction of the mean")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option(
      "--heatmap", args->heatmap,
      "Write the signed relative error as an image (.png or .exr), a colour bar with its scale below it");
  cmd->add_option("--heatmap-range", args->heatmap_range, "Relative error shown at full colour")
      ->check(CLI::Range(1e-6, 1e6));
  cmd->add_flag("--json", args->json, "Print the metrics as one JSON object");
  cmd->callback([args, &action] { action = [args] { return run_compare(*args); }; });
}

}  // namespace nimbus::cli
