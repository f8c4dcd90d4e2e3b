// libFuzzer target: volume file bytes -> a temporary file -> load_density_grid and
// inspect_volume_file (`nimbus info`). The loader picks the reader (OpenVDB or NanoVDB) from the magic
// number, never from the extension, so one load covers .vdb and .nvdb alike; the seeds hold both.
// A loaded grid is sampled at its corners, its centre and a few points derived from the input, through
// density_index, Sampler and max_density_index. Only nimbus::Error may escape the loader.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "io/vdb.h"
#include "nimbus/error.h"

// operator new as a machine with 1 GiB to spare would behave: a larger request throws std::bad_alloc.
// OpenVDB allocates whatever a corrupt size field asks for (new char[64 GiB] in io::bloscFromStream);
// in a normal build that is std::bad_alloc, which the loader turns into nimbus::Error, but ASan's own
// operator new aborts on any failed allocation. Smaller requests go to malloc, which ASan still checks
// (overflows, use after free, leaks); only new/delete mismatch detection is lost. A bad_alloc that
// escapes the loader (an allocation nimbus sized from the file outside its guards) is a finding.
constexpr std::size_t kMaxNew = std::size_t(1) << 30;
void* bounded_new(std::size_t n) {
  if (n > kMaxNew) throw std::bad_alloc();
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n) { return bounded_new(n); }
void* operator new[](std::size_t n) { return bounded_new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

namespace fs = std::filesystem;

fs::path temp_path(const char* ext) {
  return fs::temp_directory_path() / ("nimbus_vdb_fuzz_" + std::to_string(::getpid()) + ext);
}

void write_file(const fs::path& file, const uint8_t* data, size_t size) {
  std::ofstream os(file, std::ios::binary | std::ios::trunc);
  os.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

void sample(const nimbus::DensityGrid& g, const uint8_t* data, size_t size) {
  const nimbus::Vec3 lo = g.index_lo(), hi = g.index_hi();
  volatile double sink = 0;
  nimbus::DensityGrid::Sampler s(g);
  for (int c = 0; c < 8; ++c) {
    const nimbus::Vec3 p(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
    sink = sink + g.density_index(p) + s.density_index(p);
  }
  const nimbus::Vec3 mid = (lo + hi) * 0.5;
  sink = sink + g.density_index(mid) + g.max_density_index(lo, hi) + g.max_density_index(mid, mid);
  // Points from the input's last bytes, as fractions of the box (a little outside it too).
  for (size_t i = 0; i + 3 <= std::min<size_t>(size, 48); i += 3) {
    const uint8_t* b = data + size - 3 - i;
    const nimbus::Vec3 t(b[0] / 200.0 - 0.1, b[1] / 200.0 - 0.1, b[2] / 200.0 - 0.1);
    const nimbus::Vec3 p(lo.x + t.x * (hi.x - lo.x), lo.y + t.y * (hi.y - lo.y), lo.z + t.z * (hi.z - lo.z));
    sink = sink + s.density_index(p) + g.max_density_index(lo, p);
  }
  const nimbus::Bounds wb = g.world_bounds();
  sink = sink + g.world_to_index(wb.lo).x + g.index_to_world(hi).y + g.max_density() + g.stats().mean_active;
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fs::path file = temp_path(".vdb");
  write_file(file, data, size);
  try {
    const nimbus::DensityGrid g = nimbus::load_density_grid(file);
    sample(g, data, size);
  } catch (const nimbus::Error&) {
  }
  try {
    (void)nimbus::inspect_volume_file(file);
  } catch (const nimbus::Error&) {
  }
  return 0;
}
