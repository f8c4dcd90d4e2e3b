// Volume files, NanoVDB side: the .nvdb reader (validating every size against the file before it
// allocates), the structural check of a NanoVDB float grid (every node pointer inside the buffer, so a
// corrupt file cannot make the sampler read out of bounds), the statistics walk and the brick max array.
#include <blosc.h>
#include <fmt/format.h>
#include <nanovdb/util/GridChecksum.h>
#include <nanovdb/util/IO.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <limits>

#include "io/vdb_internal.h"
#include "nimbus/error.h"

namespace nimbus {

struct DensityGrid::Data {
  detail::NanoHandle handle;
  std::vector<float> bricks;
  DensityGrid::Stats stats;
};

namespace detail {
void fail(const std::filesystem::path& file, const std::string& what) {
  throw Error(fmt::format("{}: {}", file.string(), what));
}
}  // namespace detail

namespace {

namespace fs = std::filesystem;
using detail::fail;
using detail::NanoHandle;
using nanovdb::Coord;
using FloatTree = nanovdb::NanoTree<float>;
using RootT = nanovdb::NanoRoot<float>;
using UpperT = nanovdb::NanoUpper<float>;
using LowerT = nanovdb::NanoLower<float>;
using LeafT = nanovdb::NanoLeaf<float>;

constexpr uint64_t kMaxGridBytes = uint64_t(1) << 37;  // 128 GiB: anything larger is a corrupt header

// ---- file kind and size ---------------------------------------------------------------------------

enum class FileKind { OpenVDB, NanoVDB };

uint64_t checked_file_size(const fs::path& file) {
  std::error_code ec;
  const auto st = fs::status(file, ec);
  if (ec || !fs::exists(st)) fail(file, "no such file");
  if (fs::is_directory(st)) fail(file, "is a directory, not a volume file");
  if (!fs::is_regular_file(st)) fail(file, "not a regular file");
  const uint64_t size = fs::file_size(file, ec);
  if (ec) fail(file, "cannot read: " + ec.message());
  if (size == 0) fail(file, "empty file (0 bytes), not a VDB or NanoVDB file");
  return size;
}

FileKind detect_kind(const fs::path& file) {
  const uint64_t size = checked_file_size(file);
  std::ifstream is(file, std::ios::binary);
  if (!is) fail(file, "cannot open for reading");
  unsigned char head[8] = {};
  is.read(reinterpret_cast<char*>(head), static_cast<std::streamsize>(std::min<uint64_t>(size, 8)));
  if (!is) fail(file, "cannot read the file header");
  uint32_t m32 = 0;
  uint64_t m64 = 0;
  std::memcpy(&m32, head, 4);
  std::memcpy(&m64, head, 8);
  if (size >= 4 && m32 == 0x56444220u) return FileKind::OpenVDB;  // OPENVDB_MAGIC, " BDV"
  if (size >= 8 && m64 == NANOVDB_MAGIC_NUMBER) return FileKind::NanoVDB;
  if (size >= 8 && m64 == nanovdb::io::reverseEndianness(NANOVDB_MAGIC_NUMBER))
    fail(file, "NanoVDB file with reversed byte order (big-endian) is not supported");
  fail(file, "not a VDB or NanoVDB file (unrecognised header)");
}

// ---- NanoVDB files ------------------------------------------------------------------------------

// Bounds-checked reads: every read is checked against the file size first.
class FileReader {
 public:
  explicit FileReader(const fs::path& file)
      : file_(file), size_(checked_file_size(file)), is_(file, std::ios::binary) {
    if (!is_) fail(file_, "cannot open for reading");
  }
  uint64_t size() const { return size_; }
  void read(uint64_t offset, void* dst, uint64_t n, const char* what) {
    if (offset > size_ || n > size_ - offset)
      fail(file_, fmt::format("truncated or corrupt file: {} needs bytes {}..{} but the file has {} bytes",
                              what, offset, offset + n, size_));
    is_.seekg(static_cast<std::streamoff>(offset));
    is_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (!is_) fail(file_, fmt::format("read error in {}", what));
  }

 private:
  fs::path file_;
  uint64_t size_;
  std::ifstream is_;
};

struct NvdbEntry {
  nanovdb::io::GridMetaData meta;
  nanovdb::io::Codec codec = nanovdb::io::Codec::NONE;
  uint64_t offset = 0;  // of the grid's (possibly compressed) data in the file
};

// nanovdb::toStr indexes a table with the type: a corrupt file's value must be checked first
// (found by fuzz/vdb_fuzz.cpp; tests/io/fuzz_regression_test.cpp).
const char* type_name(nanovdb::GridType t) {
  return static_cast<uint32_t>(t) < static_cast<uint32_t>(nanovdb::GridType::End) ? nanovdb::toStr(t) : "invalid";
}

std::string version_string(const nanovdb::Version& v) {
  return fmt::format("{}.{}.{}", v.getMajor(), v.getMinor(), v.getPatch());
}

// Segments: [Header][MetaData + name] x gridCount [grid data] x gridCount, repeated.
std::vector<NvdbEntry> parse_nvdb(const fs::path& file, FileReader& in) {
  std::vector<NvdbEntry> entries;
  uint64_t pos = 0;
  while (pos < in.size()) {
    nanovdb::io::Header header;
    in.read(pos, &header, sizeof(header), "a NanoVDB segment header");
    if (header.magic != NANOVDB_MAGIC_NUMBER)
      fail(file, fmt::format("corrupt NanoVDB file: bad magic number in the segment header at byte {}", pos));
    pos += sizeof(header);
    if (header.version.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
      fail(file, fmt::format("NanoVDB file version {} is not supported (this build reads {}.x)",
                             version_string(header.version), NANOVDB_MAJOR_VERSION_NUMBER));
    if (header.gridCount == 0) fail(file, "corrupt NanoVDB file: a segment with no grids");
    if (static_cast<uint16_t>(header.codec) >= static_cast<uint16_t>(nanovdb::io::Codec::END))
      fail(file, fmt::format("corrupt NanoVDB file: unknown codec {}", static_cast<int>(header.codec)));
    std::vector<NvdbEntry> segment(header.gridCount);
    for (auto& e : segment) {
      in.read(pos, static_cast<nanovdb::io::MetaData*>(&e.meta), sizeof(nanovdb::io::MetaData),
              "grid metadata");
      pos += sizeof(nanovdb::io::MetaData);
      const uint32_t name_size = e.meta.nameSize;
      if (name_size == 0 || name_size > (1u << 16))
        fail(file, fmt::format("corrupt NanoVDB file: grid name of {} bytes", name_size));
      std::string name(name_size, '\0');
      in.read(pos, name.data(), name_size, "a grid name");
      pos += name_size;
      name.resize(std::strlen(name.c_str()));
      e.meta.gridName = name;
      e.codec = header.codec;
    }
    for (auto& e : segment) {
      e.offset = pos;
      if (e.meta.fileSize > in.size() - pos)
        fail(file,
             fmt::format("truncated or corrupt file: grid \"{}\" claims {} bytes at byte {} but the file "
                         "has {} bytes",
                         e.meta.gridName, e.meta.fileSize, pos, in.size()));
      pos += e.meta.fileSize;
      entries.push_back(std::move(e));
    }
  }
  return entries;
}

// Reads and decompresses one grid, checking every size before allocating.
NanoHandle read_nvdb_grid(const fs::path& file, FileReader& in, const NvdbEntry& e) {
  using nanovdb::io::Codec;
  const uint64_t grid_size = e.meta.gridSize, stored = e.meta.fileSize;
  const auto corrupt = [&](const std::string& what) {
    fail(file, fmt::format("corrupt grid \"{}\": {}", e.meta.gridName, what));
  };
  constexpr uint64_t kMinGrid = sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>) + sizeof(RootT);
  if (grid_size < kMinGrid || grid_size > kMaxGridBytes)
    corrupt(fmt::format("impossible grid size {} bytes", grid_size));
  // Sizes of the compressed chunks, validated against the grid size before allocating it.
  std::vector<std::pair<uint64_t, uint64_t>> chunks;  // (file offset of compressed bytes, compressed bytes)
  if (e.codec == Codec::NONE) {
    if (stored != grid_size) corrupt(fmt::format("{} bytes stored for a {} byte grid", stored, grid_size));
  } else {
    uint64_t p = e.offset, residual = grid_size;
    const uint64_t end = e.offset + stored;
    do {
      uint64_t csize = 0;
      if (end - p < 8) corrupt("compressed data truncated");
      in.read(p, &csize, 8, "a compressed chunk size");
      p += 8;
      if (csize > end - p)
        corrupt(fmt::format("compressed chunk of {} bytes overruns the grid's data", csize));
      const uint64_t chunk =
          e.codec == Codec::BLOSC ? std::min<uint64_t>(residual, uint64_t(1) << 30) : residual;
      if (e.codec == Codec::ZIP) {
        if (grid_size > 1040 * csize + 1024)  // zlib cannot compress better than ~1032:1
          corrupt(fmt::format("{} bytes cannot inflate to {} bytes", csize, grid_size));
      } else {
        unsigned char bh[BLOSC_MIN_HEADER_LENGTH];
        if (csize < sizeof(bh)) corrupt("BLOSC chunk too small");
        in.read(p, bh, sizeof(bh), "a BLOSC header");
        size_t nbytes = 0;
        if (blosc_cbuffer_validate(bh, csize, &nbytes) != 0 || nbytes != chunk)
          corrupt(fmt::format("BLOSC header does not match the grid size ({} bytes expected)", chunk));
      }
      chunks.emplace_back(p, csize);
      p += csize;
      residual -= chunk;
    } while (residual > 0);
  }
  nanovdb::HostBuffer buffer;
  try {
    buffer = nanovdb::HostBuffer::create(grid_size);
  } catch (const std::exception&) {
    fail(file, fmt::format("cannot allocate {} bytes for grid \"{}\"", grid_size, e.meta.gridName));
  }
  if (buffer.data() == nullptr) fail(file, fmt::format("cannot allocate {} bytes", grid_size));
  auto* dst = buffer.data();
  if (e.codec == Codec::NONE) {
    in.read(e.offset, dst, grid_size, "grid data");
  } else if (e.codec == Codec::ZIP) {
    std::vector<Bytef> src(chunks[0].second);
    in.read(chunks[0].first, src.data(), src.size(), "ZIP data");
    uLongf n = static_cast<uLongf>(grid_size);
    if (uncompress(dst, &n, src.data(), static_cast<uLong>(src.size())) != Z_OK || n != grid_size)
      corrupt("ZIP data does not inflate to the grid size");
  } else {
    uint64_t residual = grid_size;
    for (const auto& [offset, csize] : chunks) {
      std::vector<char> src(csize);
      in.read(offset, src.data(), csize, "BLOSC data");
      const uint64_t chunk = std::min<uint64_t>(residual, uint64_t(1) << 30);
      if (blosc_decompress_ctx(src.data(), dst, chunk, 1) != static_cast<int>(chunk))
        corrupt("BLOSC data does not decompress to the grid size");
      dst += chunk;
      residual -= chunk;
    }
  }
  return NanoHandle(std::move(buffer));
}

// ---- structural check and statistics walk ----------------------------------------------------------

// The grid in a buffer check_and_walk has accepted (magic, size, float type). GridHandle::grid<float>()
// must not be used on file data: it follows the header's grid index by hopping mGridSize bytes (a
// corrupt index read past the buffer; a grid read alone from a multi-grid file keeps its index too).
const nanovdb::FloatGrid* checked_float_grid(const NanoHandle& handle) {
  return reinterpret_cast<const nanovdb::FloatGrid*>(handle.data());
}

struct Walk {
  uint64_t active_voxels = 0, tiles = 0;
  uint32_t nodes[3] = {0, 0, 0};  // leaf, lower, upper
  nanovdb::CoordBBox bbox;        // of the active values; empty if none
  std::string name;               // the grid's name, read with bounds checks
  double min = std::numeric_limits<double>::infinity(), max = -min, sum = 0;
  void add(double v, uint64_t count, const Coord& lo, int dim) {
    active_voxels += count;
    min = std::min(min, v);
    max = std::max(max, v);
    sum += v * static_cast<double>(count);
    bbox.expand(lo);
    bbox.expand(lo + Coord(dim - 1));
  }
};

// Checks the grid header, the tree, the root table and every child pointer (inside the buffer, 32-byte
// aligned, with room for the node), then gathers the statistics. Node origins are derived top-down
// from the root keys, as the ReadAccessor navigates.
Walk check_and_walk(const fs::path& file, const NanoHandle& handle) {
  const uint8_t* base = handle.data();
  const uint64_t size = handle.size();
  const auto corrupt = [&](const std::string& what) { fail(file, "corrupt grid data: " + what); };
  if (size < sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>) + sizeof(RootT))
    corrupt("buffer too small");
  const auto* gd = reinterpret_cast<const nanovdb::GridData*>(base);
  if (gd->mMagic != NANOVDB_MAGIC_NUMBER) corrupt("bad magic number");
  if (gd->mGridSize != size) corrupt(fmt::format("grid size {} != buffer size {}", gd->mGridSize, size));
  if (gd->mVersion.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
    corrupt(fmt::format("grid version {}", version_string(gd->mVersion)));
  if (gd->mGridType != nanovdb::GridType::Float)
    fail(file, fmt::format("grid is not a float grid (type {})", type_name(gd->mGridType)));
  const auto& grid = *reinterpret_cast<const nanovdb::FloatGrid*>(base);
  for (int a = 0; a < 3; ++a)
    if (!(gd->mVoxelSize[a] > 0 && std::isfinite(gd->mVoxelSize[a]))) corrupt("bad voxel size");
  // Tree and root node.
  const uint64_t tree_off = sizeof(nanovdb::GridData);
  const auto* td = reinterpret_cast<const nanovdb::TreeData<3>*>(base + tree_off);
  const uint64_t root_off = tree_off + td->mNodeOffset[3];
  if (td->mNodeOffset[3] > size || root_off % 32 != 0 || root_off > size - sizeof(RootT))
    corrupt("bad root offset");
  const auto* root = reinterpret_cast<const typename RootT::DataType*>(base + root_off);
  if (root->mTableSize > (size - root_off - sizeof(RootT)) / sizeof(typename RootT::Tile))
    corrupt("root table overruns the buffer");
  const uint64_t nodes_begin = root_off + sizeof(RootT) + root->mTableSize * sizeof(typename RootT::Tile);
  // A child at byte offset `parent + rel` must lie inside [nodes_begin, size - node_size], 32B aligned.
  const auto child_off = [&](uint64_t parent, int64_t rel, uint64_t node_size) -> uint64_t {
    const uint64_t c = parent + static_cast<uint64_t>(rel);  // wraps for bad negative offsets
    if (c < nodes_begin || c > size || node_size > size - c || c % 32 != 0)
      corrupt(
          fmt::format("node pointer outside the buffer (offset {} of {})", static_cast<int64_t>(c), size));
    return c;
  };
  Walk w;
  for (uint32_t t = 0; t < root->mTableSize; ++t) {
    const auto* tile = root->tile(t);
    const Coord o2 = tile->origin();
    // Node origins are derived from this one by adding offsets: keep every voxel of the 4096^3 node
    // representable (a corrupt key near INT_MAX would overflow in Coord arithmetic).
    for (int a = 0; a < 3; ++a)
      if (o2[a] < -detail::kMaxIndexCoord || o2[a] > detail::kMaxIndexCoord - 4096) corrupt("root tile origin out of range");
    if (!tile->isChild()) {
      if (tile->state) w.tiles++, w.add(tile->value, uint64_t(1) << 36, o2, 4096);
      continue;
    }
    const uint64_t off2 = child_off(root_off, tile->child, sizeof(UpperT));
    const auto* up = reinterpret_cast<const typename UpperT::DataType*>(base + off2);
    w.nodes[2]++;
    for (uint32_t n2 = 0; n2 < 32768; ++n2) {
      const Coord o1 = o2 + (UpperT::OffsetToLocalCoord(n2) << 7);
      if (!up->mChildMask.isOn(n2)) {
        if (up->mValueMask.isOn(n2)) w.tiles++, w.add(up->mTable[n2].value, uint64_t(1) << 21, o1, 128);
        continue;
      }
      const uint64_t off1 = child_off(off2, up->mTable[n2].child, sizeof(LowerT));
      const auto* lo = reinterpret_cast<const typename LowerT::DataType*>(base + off1);
      w.nodes[1]++;
      for (uint32_t n1 = 0; n1 < 4096; ++n1) {
        const Coord o0 = o1 + (LowerT::OffsetToLocalCoord(n1) << 3);
        if (!lo->mChildMask.isOn(n1)) {
          if (lo->mValueMask.isOn(n1)) w.tiles++, w.add(lo->mTable[n1].value, 512, o0, 8);
          continue;
        }
        const uint64_t off0 = child_off(off1, lo->mTable[n1].child, sizeof(LeafT));
        const auto* leaf = reinterpret_cast<const typename LeafT::DataType*>(base + off0);
        w.nodes[0]++;
        for (uint32_t n = 0; n < 512; ++n)
          if (leaf->mValueMask.isOn(n)) w.add(leaf->mValues[n], 1, o0 + LeafT::OffsetToLocalCoord(n), 1);
      }
    }
  }
  // The node manager (used by the full checksum) trusts the tree's node counts and first-node offsets.
  for (int l = 0; l < 3; ++l) {
    if (td->mNodeCount[l] != w.nodes[l]) corrupt(fmt::format("node count mismatch at level {}", l));
    const uint64_t node_size = l == 0 ? sizeof(LeafT) : l == 1 ? sizeof(LowerT) : sizeof(UpperT);
    if (w.nodes[l] > 0 && grid.isBreadthFirst()) {
      const uint64_t first = tree_off + td->mNodeOffset[l];
      if (td->mNodeOffset[l] > size || first < nodes_begin || w.nodes[l] > (size - first) / node_size)
        corrupt(fmt::format("node array at level {} overruns the buffer", l));
    }
  }
  // The name: nanovdb's gridName() follows a long name's blind metadata (offset and count from the
  // file) without checks, and a short name need not be NUL-terminated in a corrupt file.
  if (gd->mFlags & static_cast<uint32_t>(nanovdb::GridFlags::HasLongGridName)) {
    using Meta = nanovdb::GridBlindMetaData;
    const uint32_t count = gd->mBlindMetadataCount;
    const int64_t meta_rel = gd->mBlindMetadataOffset;
    if (count == 0 || meta_rel < 0 || static_cast<uint64_t>(meta_rel) > size ||
        count > (size - static_cast<uint64_t>(meta_rel)) / sizeof(Meta))
      corrupt("blind metadata outside the buffer");
    const uint64_t meta_off = static_cast<uint64_t>(meta_rel) + (count - 1) * sizeof(Meta);
    const auto* meta = reinterpret_cast<const Meta*>(base + meta_off);
    const uint64_t name_off = meta_off + static_cast<uint64_t>(meta->mByteOffset);  // wraps if negative
    if (meta->mDataClass != nanovdb::GridBlindDataClass::GridName || name_off >= size)
      corrupt("long grid name outside the buffer");
    const char* name = reinterpret_cast<const char*>(base + name_off);
    const size_t n = strnlen(name, static_cast<size_t>(size - name_off));
    if (n == size - name_off) corrupt("long grid name is not terminated");
    w.name.assign(name, n);
  } else {
    w.name.assign(gd->mGridName, strnlen(gd->mGridName, nanovdb::GridData::MaxNameSize));
  }
  // The map: index -> world -> index must round-trip.
  const nanovdb::Vec3d p(1.5, -2.25, 3.75), q = grid.worldToIndex(grid.indexToWorld(p));
  if (!((q - p).length() < 1e-6)) corrupt("singular or non-finite index-to-world map");
  (void)grid;
  return w;
}

void check_bbox(const fs::path& file, const Walk& w) {
  if (w.active_voxels == 0) fail(file, "empty grid: no active voxels");
  const auto& b = w.bbox;
  double voxels = 1;
  for (int a = 0; a < 3; ++a) {
    voxels *= static_cast<double>(b.max()[a]) - b.min()[a] + 1.0;
    if (std::abs(b.min()[a]) > (1 << 30) || std::abs(b.max()[a]) > (1 << 30))
      fail(file, "index bbox coordinates beyond +-2^30");
  }
  if (voxels > detail::kMaxBBoxVoxels)
    fail(file,
         fmt::format("index bbox [{}, {}, {}]..[{}, {}, {}] holds {:.3g} voxels (more than 2^31): too large",
                     b.min()[0], b.min()[1], b.min()[2], b.max()[0], b.max()[1], b.max()[2], voxels));
}

NanoHandle open_nvdb_grid(const fs::path& file, const std::string& grid_name) {
  FileReader in(file);
  const auto entries = parse_nvdb(file, in);
  const NvdbEntry* chosen = nullptr;
  for (const auto& e : entries) {
    if (grid_name.empty() ? e.meta.gridType == nanovdb::GridType::Float : e.meta.gridName == grid_name) {
      chosen = &e;
      break;
    }
  }
  if (chosen == nullptr || chosen->meta.gridType != nanovdb::GridType::Float) {
    std::string list;
    for (const auto& e : entries)
      list += fmt::format("{}\"{}\" ({})", list.empty() ? "" : ", ", e.meta.gridName,
                          type_name(e.meta.gridType));
    if (chosen != nullptr)
      fail(file, fmt::format("grid \"{}\" is of type {}, not float", grid_name,
                             type_name(chosen->meta.gridType)));
    if (grid_name.empty()) fail(file, "no float grid in the file; it holds " + list);
    fail(file, fmt::format("no grid named \"{}\"; the file holds {}", grid_name, list));
  }
  return read_nvdb_grid(file, in, *chosen);
}

}  // namespace

// ---- DensityGrid ----------------------------------------------------------------------------------

DensityGrid DensityGrid::load(const std::filesystem::path& file, const std::string& grid_name) {
  const auto t0 = std::chrono::steady_clock::now();
  const FileKind kind = detect_kind(file);
  NanoHandle handle = kind == FileKind::OpenVDB ? detail::load_openvdb_float_grid(file, grid_name)
                                                : open_nvdb_grid(file, grid_name);
  const double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return analyse(file, std::move(handle), read_seconds, kind == FileKind::NanoVDB);
}

DensityGrid DensityGrid::from_nanovdb(nanovdb::GridHandle<nanovdb::HostBuffer> handle, const std::string& source) {
  return analyse(source, std::move(handle), 0.0);
}

DensityGrid DensityGrid::analyse(const std::filesystem::path& file, nanovdb::GridHandle<nanovdb::HostBuffer> handle,
                                 double read_seconds, bool verify_checksum) {
  const auto t1 = std::chrono::steady_clock::now();
  auto data = std::make_shared<Data>();
  data->handle = std::move(handle);
  const Walk w = check_and_walk(file, data->handle);
  const auto* grid = checked_float_grid(data->handle);
  // Only after the structural check: the checksum reads the root table and every node through the
  // grid's own sizes and offsets (a corrupt root table size read past the buffer; see
  // tests/io/fuzz_regression_test.cpp).
  if (verify_checksum && !nanovdb::validateChecksum(*grid, nanovdb::ChecksumMode::Full))
    fail(file, "corrupt grid data: checksum mismatch");
  check_bbox(file, w);

  DensityGrid g;
  g.grid_ = grid;
  for (int a = 0; a < 3; ++a) {
    g.lo_i_[a] = w.bbox.min()[a] - 1;
    g.lo_[a] = g.lo_i_[a];
    g.hi_[a] = w.bbox.max()[a] + 1;
    g.brick_n_[a] = ((w.bbox.max()[a] + 1 - g.lo_i_[a]) >> 3) + 1;
  }
  const int nx = g.brick_n_[0], ny = g.brick_n_[1], nz = g.brick_n_[2];
  const int hi_i[3] = {w.bbox.max()[0] + 1, w.bbox.max()[1] + 1, w.bbox.max()[2] + 1};
  data->bricks.assign(static_cast<size_t>(nx) * ny * nz, 0.0f);

  // Brick max over every voxel the sampler can read (cells [lo, hi] and their +1 neighbours), dilated
  // by one voxel; the same pass counts NaN/inf and negative values, each voxel once (in the brick whose
  // cells hold it; the last brick per axis also owns voxel hi + 1).
  struct Row {
    uint64_t bad = 0, negative = 0;
    Coord first_bad;
  };
  std::vector<Row> rows(static_cast<size_t>(ny) * nz);
  tbb::parallel_for(tbb::blocked_range<int>(0, ny * nz), [&](const tbb::blocked_range<int>& r) {
    auto acc = grid->getAccessor();
    for (int row = r.begin(); row < r.end(); ++row) {
      const int by = row % ny, bz = row / ny;
      Row& out = rows[row];
      for (int bx = 0; bx < nx; ++bx) {
        const int b[3] = {bx, by, bz};
        int s[3], e[3], own_hi[3];
        for (int a = 0; a < 3; ++a) {
          s[a] = g.lo_i_[a] + 8 * b[a];
          e[a] = std::min(s[a] + 7, hi_i[a]);
          own_hi[a] = s[a] + 7 < hi_i[a] ? s[a] + 7 : hi_i[a] + 1;
        }
        // The voxels s - 1 ... e + 1 per axis, one leaf-sized block (8^3, aligned) at a time: a block
        // with a leaf is read voxel by voxel; a block without one holds a single tile or background
        // value, read once. So the cost follows the data, not the empty space in the bbox (a sparse
        // 300 KB file whose bbox holds 2^31 voxels took minutes; found by fuzz/vdb_fuzz.cpp).
        float m = 0.0f;
        const uint64_t bad_before = out.bad;
        Coord brick_first_bad;
        const auto note_bad = [&](const Coord& c, uint64_t n) {
          const bool less = c[0] != brick_first_bad[0]   ? c[0] < brick_first_bad[0]
                            : c[1] != brick_first_bad[1] ? c[1] < brick_first_bad[1]
                                                         : c[2] < brick_first_bad[2];
          if (out.bad == bad_before || less) brick_first_bad = c;
          out.bad += n;
        };
        const int r0[3] = {s[0] - 1, s[1] - 1, s[2] - 1}, r1[3] = {e[0] + 1, e[1] + 1, e[2] + 1};
        for (int ox = r0[0] & ~7; ox <= r1[0]; ox += 8)
          for (int oy = r0[1] & ~7; oy <= r1[1]; oy += 8)
            for (int oz = r0[2] & ~7; oz <= r1[2]; oz += 8) {
              const int o[3] = {ox, oy, oz};
              int b0[3], b1[3];
              for (int a = 0; a < 3; ++a) b0[a] = std::max(o[a], r0[a]), b1[a] = std::min(o[a] + 7, r1[a]);
              if (const auto* leaf = acc.probeLeaf(Coord(ox, oy, oz))) {
                for (int i = b0[0]; i <= b1[0]; ++i)
                  for (int j = b0[1]; j <= b1[1]; ++j)
                    for (int k = b0[2]; k <= b1[2]; ++k) {
                      const float v = leaf->getValue(Coord(i, j, k));
                      m = std::max(m, v);
                      if (i < s[0] || j < s[1] || k < s[2] || i > own_hi[0] || j > own_hi[1] || k > own_hi[2])
                        continue;
                      if (!std::isfinite(v)) {
                        note_bad(Coord(i, j, k), 1);
                      } else if (v < 0.0f) {
                        out.negative++;
                      }
                    }
                continue;
              }
              const float v = acc.getValue(Coord(ox, oy, oz));
              m = std::max(m, v);
              // The voxels of this block that this brick owns.
              uint64_t n = 1;
              int c0[3];
              for (int a = 0; a < 3; ++a) {
                c0[a] = std::max(b0[a], s[a]);
                const int c1 = std::min(b1[a], own_hi[a]);
                n = c1 < c0[a] ? 0 : n * static_cast<uint64_t>(c1 - c0[a] + 1);
              }
              if (n == 0) continue;
              if (!std::isfinite(v)) {
                note_bad(Coord(c0[0], c0[1], c0[2]), n);
              } else if (v < 0.0f) {
                out.negative += n;
              }
            }
        if (out.bad > bad_before && bad_before == 0) out.first_bad = brick_first_bad;
        data->bricks[(static_cast<size_t>(bz) * ny + by) * nx + bx] = static_cast<float>(m * (1.0 + 1e-6));
      }
    }
  });
  uint64_t bad = 0, negative = 0;
  Coord first_bad;
  for (const Row& row : rows) {
    if (row.bad > 0 && bad == 0) first_bad = row.first_bad;
    bad += row.bad;
    negative += row.negative;
  }
  if (bad > 0) {
    const auto wp = grid->indexToWorld(nanovdb::Vec3d(first_bad[0], first_bad[1], first_bad[2]));
    fail(file, fmt::format(
                   "{} NaN/inf density values (first at index [{}, {}, {}], world ({:.6g}, {:.6g}, {:.6g}))",
                   bad, first_bad[0], first_bad[1], first_bad[2], wp[0], wp[1], wp[2]));
  }

  Stats& st = data->stats;
  st.name = w.name;
  st.file = file.string();
  st.active_voxels = w.active_voxels;
  st.tiles = w.tiles;
  st.voxel_size = Vec3(grid->voxelSize()[0], grid->voxelSize()[1], grid->voxelSize()[2]);
  for (int a = 0; a < 3; ++a) st.index_min[a] = w.bbox.min()[a], st.index_max[a] = w.bbox.max()[a];
  st.min_value = w.min;
  st.max_value = w.max;
  st.mean_active = w.sum / static_cast<double>(w.active_voxels);
  st.negative_count = negative;
  st.read_seconds = read_seconds;
  st.analyse_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  g.max_density_ = *std::max_element(data->bricks.begin(), data->bricks.end());
  g.bricks_ = data->bricks.data();
  g.data_ = std::move(data);
  return g;
}

Vec3 DensityGrid::world_to_index(const Vec3& p) const {
  const auto q = grid_->worldToIndex(nanovdb::Vec3d(p.x, p.y, p.z));
  return {q[0], q[1], q[2]};
}

Vec3 DensityGrid::index_to_world(const Vec3& p) const {
  const auto q = grid_->indexToWorld(nanovdb::Vec3d(p.x, p.y, p.z));
  return {q[0], q[1], q[2]};
}

Bounds DensityGrid::world_bounds() const {
  Bounds b;
  for (int c = 0; c < 8; ++c)
    b.extend(index_to_world({c & 1 ? hi_.x : lo_.x, c & 2 ? hi_.y : lo_.y, c & 4 ? hi_.z : lo_.z}));
  return b;
}

const DensityGrid::Stats& DensityGrid::stats() const { return data_->stats; }

double DensityGrid::max_density_index(const Vec3& a, const Vec3& b) const {
  // Cells touched by the box, clipped to [lo, hi]; a point p in cell c reads voxels c and c + 1,
  // which the dilated brick max of c's brick covers.
  int b0[3], b1[3];
  for (int i = 0; i < 3; ++i) {
    const double l = std::max(a[i], lo_[i]), h = std::min(b[i], hi_[i]);
    if (!(l <= h)) return 0.0;
    b0[i] = std::min((static_cast<int>(std::floor(l)) - lo_i_[i]) >> 3, brick_n_[i] - 1);
    b1[i] = std::min((static_cast<int>(std::floor(h)) - lo_i_[i]) >> 3, brick_n_[i] - 1);
  }
  float m = 0.0f;
  for (int z = b0[2]; z <= b1[2]; ++z)
    for (int y = b0[1]; y <= b1[1]; ++y) {
      const float* row = bricks_ + (static_cast<size_t>(z) * brick_n_[1] + y) * brick_n_[0];
      for (int x = b0[0]; x <= b1[0]; ++x) m = std::max(m, row[x]);
    }
  return m;
}

// ---- inspect --------------------------------------------------------------------------------------

namespace {

const char* class_name(nanovdb::GridClass c) {
  static const char* names[] = {"unknown",    "level set", "fog volume",   "staggered", "point index",
                                "point data", "topology",  "voxel volume", "index grid"};
  const auto i = static_cast<uint32_t>(c);
  return i < std::size(names) ? names[i] : "invalid";
}

std::vector<GridInfo> inspect_nvdb_file(const fs::path& file) {
  FileReader in(file);
  const auto entries = parse_nvdb(file, in);
  std::vector<GridInfo> out;
  for (const auto& e : entries) {
    GridInfo gi;
    const auto& m = e.meta;
    gi.name = m.gridName;
    gi.type = type_name(m.gridType);
    gi.grid_class = class_name(m.gridClass);
    gi.active_voxels = m.voxelCount;
    gi.tiles = uint64_t(m.tileCount[0]) + m.tileCount[1] + m.tileCount[2];
    gi.empty = m.voxelCount == 0;
    for (int a = 0; a < 3; ++a) {
      gi.index_min[a] = m.indexBBox.min()[a];
      gi.index_max[a] = m.indexBBox.max()[a];
      gi.voxel_size[a] = m.voxelSize[a];
    }
    // Non-float grids: NanoVDB's stored world bbox (covers whole voxels).
    gi.world_bounds.extend(Vec3(m.worldBBox.min()[0], m.worldBBox.min()[1], m.worldBBox.min()[2]));
    gi.world_bounds.extend(Vec3(m.worldBBox.max()[0], m.worldBBox.max()[1], m.worldBBox.max()[2]));
    if (m.gridType == nanovdb::GridType::Float) {
      // Float grids: read them and recount from the data itself.
      const NanoHandle h = read_nvdb_grid(file, in, e);
      const Walk w = check_and_walk(file, h);
      const auto* grid = checked_float_grid(h);
      gi.active_voxels = w.active_voxels;
      gi.tiles = w.tiles;
      gi.empty = w.active_voxels == 0;
      gi.world_bounds = Bounds{};
      if (!gi.empty) {
        for (int a = 0; a < 3; ++a) gi.index_min[a] = w.bbox.min()[a], gi.index_max[a] = w.bbox.max()[a];
        for (int c = 0; c < 8; ++c) {
          const nanovdb::Vec3d p(c & 1 ? gi.index_max[0] : gi.index_min[0],
                                 c & 2 ? gi.index_max[1] : gi.index_min[1],
                                 c & 4 ? gi.index_max[2] : gi.index_min[2]);
          const auto q = grid->indexToWorld(p);
          gi.world_bounds.extend(Vec3(q[0], q[1], q[2]));
        }
        gi.has_value_range = true;
        gi.min_value = w.min;
        gi.max_value = w.max;
        gi.mean_active = w.sum / static_cast<double>(w.active_voxels);
      }
    }
    out.push_back(std::move(gi));
  }
  return out;
}

}  // namespace

std::vector<GridInfo> inspect_volume_file(const std::filesystem::path& file) {
  return detect_kind(file) == FileKind::OpenVDB ? detail::inspect_openvdb_file(file)
                                                : inspect_nvdb_file(file);
}

}  // namespace nimbus
