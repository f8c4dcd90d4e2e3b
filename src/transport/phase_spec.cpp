// Phase functions from short command-line specs (phase_spec.h).
#include "transport/phase_spec.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "media/fournier_forand.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

std::vector<double> parse_numbers(const std::string& spec, const std::string& list, size_t count) {
  const std::vector<double> v = parse_number_list(fmt::format("phase '{}'", spec), list);
  if (v.size() != count)
    throw Error(fmt::format("phase '{}': expected {} number(s), got {}", spec, count, v.size()));
  return v;
}

void check_g(const std::string& spec, double g) {
  if (!(g > -1.0 && g < 1.0)) throw Error(fmt::format("phase '{}': asymmetry g must lie in (-1, 1)", spec));
}

}  // namespace

std::vector<double> parse_number_list(const std::string& what, const std::string& list) {
  std::vector<double> v;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    double x = 0.0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(x))
      throw Error(fmt::format("{}: '{}' is not a number", what, item));
    v.push_back(x);
  }
  if (v.empty()) throw Error(fmt::format("{}: empty list", what));
  return v;
}

std::string phase_table_dir() {
  if (const char* d = std::getenv("NIMBUS_DATA_DIR"); d && *d) return std::string(d) + "/phase";
  // Installed (cmake --install --prefix P): P/share/nimbus/phase beside P/bin/nimbus, or where the build
  // configured the prefix.
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path dir = exe.parent_path().parent_path() / "share" / "nimbus" / "phase";
    if (std::filesystem::is_directory(dir, ec)) return dir.string();
  }
#ifdef NIMBUS_INSTALL_DATA_DIR
  if (std::filesystem::is_directory(NIMBUS_INSTALL_DATA_DIR "/phase", ec))
    return NIMBUS_INSTALL_DATA_DIR "/phase";
#endif
  return std::string(NIMBUS_SOURCE_DIR) + "/data/phase";
}

bool is_phase_table_name(const std::string& name) {
  return !name.empty() && name[0] != '.' &&
         name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.") ==
             std::string::npos;
}

TabulatedPhase load_phase_table(const std::string& name, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(fmt::format("phase table '{}': cannot open {}", name, path));
  std::vector<double> theta, value;
  std::string line;
  int row = 0;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty() || line[0] == '#') continue;
    double t = 0.0, v = 0.0;
    char comma = 0;
    std::istringstream ls(line);
    if (!(ls >> t >> comma >> v) || comma != ',') {
      if (theta.empty()) continue;  // a header line before the data
      throw Error(fmt::format("{}:{}: expected 'theta,value'", path, row));
    }
    theta.push_back(t);
    value.push_back(v);
  }
  return make_tabulated_phase(name, std::move(theta), std::move(value));
}

Phase parse_phase_spec(const std::string& spec) {
  const size_t colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string args = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "iso" || kind == "isotropic") {
    if (colon != std::string::npos) throw Error(fmt::format("phase '{}': iso takes no parameters", spec));
    return IsotropicPhase{};
  }
  if (kind == "hg") {
    const double g = parse_numbers(spec, args, 1)[0];
    check_g(spec, g);
    return HgPhase{g};
  }
  if (kind == "dhg") {
    const auto v = parse_numbers(spec, args, 3);
    check_g(spec, v[0]);
    check_g(spec, v[1]);
    if (!(v[2] >= 0.0 && v[2] <= 1.0))
      throw Error(fmt::format("phase '{}': weight W must lie in [0, 1]", spec));
    return DoubleHgPhase{v[0], v[1], v[2]};
  }
  if (kind == "gauss") {
    const double t = parse_numbers(spec, args, 1)[0];
    if (!(t > 0.0 && t < 1.0)) throw Error(fmt::format("phase '{}': theta2 must lie in (0, 1)", spec));
    return make_gauss_phase(t);
  }
  if (kind == "mie") {
    // A path (holds '/' or ends in .csv): that file; otherwise a table of phase_table_dir().
    if (args.find('/') != std::string::npos ||
        (args.size() > 4 && args.compare(args.size() - 4, 4, ".csv") == 0))
      return load_phase_table(std::filesystem::path(args).stem().string(), args);
    if (!is_phase_table_name(args))
      throw Error(fmt::format("phase '{}': mie needs a table name of letters, digits, '_', '-', '.'", spec));
    return load_phase_table(args, phase_table_dir() + "/" + args + ".csv");
  }
  if (kind == "ff") {
    const auto v = parse_numbers(spec, args, 2);
    if (!ff_parameters_valid(v[0], v[1]))
      throw Error(fmt::format("phase '{}': Fournier-Forand needs n in (1, 1.5] and mu in (3, 5]", spec));
    return make_ff_phase(v[0], v[1]);
  }
  if (kind == "ffb") {
    const double b = parse_numbers(spec, args, 1)[0];
    double mu = 0.0;
    try {
      mu = ff_mobley_mu(b);
    } catch (const Error& e) {
      throw Error(fmt::format("phase '{}': {}", spec, e.what()));
    }
    return make_ff_phase(ff_mobley_n(mu), mu);
  }
  throw Error(fmt::format(
      "phase '{}': unknown type (use iso, hg:G, dhg:G1,G2,W, gauss:THETA2, mie:NAME, mie:FILE.csv, "
      "ff:N,MU or ffb:B)",
      spec));
}

}  // namespace nimbus
