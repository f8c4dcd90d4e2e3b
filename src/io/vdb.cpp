// Volume files, NanoVDB side: the .nvdb reader (validating every size against the file before it
// allocates), the structural check of a NanoVDB float grid read from a file (every node pointer inside
// the buffer, so a corrupt file cannot make the sampler read out of bounds), load_density_grid and
// inspect_volume_file. The in-memory grid (statistics, value checks, brick max) is
// media/density_grid.cpp's.
#include <blosc.h>
#include <fmt/format.h>
#include <nanovdb/util/GridChecksum.h>
#include <nanovdb/util/IO.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <limits>

#include "io/vdb_internal.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

namespace fs = std::filesystem;
using detail::fail;
using detail::NanoHandle;
using nanovdb::Coord;
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
  return static_cast<uint32_t>(t) < static_cast<uint32_t>(nanovdb::GridType::End) ? nanovdb::toStr(t)
                                                                                  : "invalid";
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

// Sizes of the compressed chunks of a grid, validated against the grid size before it is allocated:
// (file offset of the compressed bytes, compressed bytes) per chunk. None for an uncompressed grid.
using Chunks = std::vector<std::pair<uint64_t, uint64_t>>;

[[noreturn]] void corrupt_grid(const fs::path& file, const NvdbEntry& e, const std::string& what) {
  fail(file, fmt::format("corrupt grid \"{}\": {}", e.meta.gridName, what));
}

Chunks plan_chunks(const fs::path& file, FileReader& in, const NvdbEntry& e) {
  using nanovdb::io::Codec;
  const uint64_t grid_size = e.meta.gridSize, stored = e.meta.fileSize;
  Chunks chunks;
  if (e.codec == Codec::NONE) {
    if (stored != grid_size)
      corrupt_grid(file, e, fmt::format("{} bytes stored for a {} byte grid", stored, grid_size));
    return chunks;
  }
  uint64_t p = e.offset, residual = grid_size;
  const uint64_t end = e.offset + stored;
  do {
    uint64_t csize = 0;
    if (end - p < 8) corrupt_grid(file, e, "compressed data truncated");
    in.read(p, &csize, 8, "a compressed chunk size");
    p += 8;
    if (csize > end - p)
      corrupt_grid(file, e, fmt::format("compressed chunk of {} bytes overruns the grid's data", csize));
    const uint64_t chunk =
        e.codec == Codec::BLOSC ? std::min<uint64_t>(residual, uint64_t(1) << 30) : residual;
    if (e.codec == Codec::ZIP) {
      if (grid_size > 1040 * csize + 1024)  // zlib cannot compress better than ~1032:1
        corrupt_grid(file, e, fmt::format("{} bytes cannot inflate to {} bytes", csize, grid_size));
    } else {
      unsigned char bh[BLOSC_MIN_HEADER_LENGTH];
      if (csize < sizeof(bh)) corrupt_grid(file, e, "BLOSC chunk too small");
      in.read(p, bh, sizeof(bh), "a BLOSC header");
      size_t nbytes = 0;
      if (blosc_cbuffer_validate(bh, csize, &nbytes) != 0 || nbytes != chunk)
        corrupt_grid(file, e,
                     fmt::format("BLOSC header does not match the grid size ({} bytes expected)", chunk));
    }
    chunks.emplace_back(p, csize);
    p += csize;
    residual -= chunk;
  } while (residual > 0);
  return chunks;
}

// Fills dst (grid_size bytes) from the file: a plain copy, or the planned chunks decompressed.
void read_grid_bytes(const fs::path& file, FileReader& in, const NvdbEntry& e, const Chunks& chunks,
                     uint8_t* dst) {
  using nanovdb::io::Codec;
  const uint64_t grid_size = e.meta.gridSize;
  if (e.codec == Codec::NONE) {
    in.read(e.offset, dst, grid_size, "grid data");
  } else if (e.codec == Codec::ZIP) {
    std::vector<Bytef> src(chunks[0].second);
    in.read(chunks[0].first, src.data(), src.size(), "ZIP data");
    uLongf n = static_cast<uLongf>(grid_size);
    if (uncompress(dst, &n, src.data(), static_cast<uLong>(src.size())) != Z_OK || n != grid_size)
      corrupt_grid(file, e, "ZIP data does not inflate to the grid size");
  } else {
    uint64_t residual = grid_size;
    for (const auto& [offset, csize] : chunks) {
      std::vector<char> src(csize);
      in.read(offset, src.data(), csize, "BLOSC data");
      const uint64_t chunk = std::min<uint64_t>(residual, uint64_t(1) << 30);
      if (blosc_decompress_ctx(src.data(), dst, chunk, 1) != static_cast<int>(chunk))
        corrupt_grid(file, e, "BLOSC data does not decompress to the grid size");
      dst += chunk;
      residual -= chunk;
    }
  }
}

// Reads and decompresses one grid, checking every size before allocating.
NanoHandle read_nvdb_grid(const fs::path& file, FileReader& in, const NvdbEntry& e) {
  const uint64_t grid_size = e.meta.gridSize;
  constexpr uint64_t kMinGrid = sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>) + sizeof(RootT);
  if (grid_size < kMinGrid || grid_size > kMaxGridBytes)
    corrupt_grid(file, e, fmt::format("impossible grid size {} bytes", grid_size));
  const Chunks chunks = plan_chunks(file, in, e);
  nanovdb::HostBuffer buffer;
  try {
    buffer = nanovdb::HostBuffer::create(grid_size);
  } catch (const std::exception&) {
    fail(file, fmt::format("cannot allocate {} bytes for grid \"{}\"", grid_size, e.meta.gridName));
  }
  if (buffer.data() == nullptr) fail(file, fmt::format("cannot allocate {} bytes", grid_size));
  read_grid_bytes(file, in, e, chunks, buffer.data());
  return NanoHandle(std::move(buffer));
}

// ---- structural check -----------------------------------------------------------------------------

// The grid in a buffer check_grid_structure has accepted (magic, size, float type). GridHandle::grid<float>()
// must not be used on file data: it follows the header's grid index by hopping mGridSize bytes (a
// corrupt index read past the buffer; a grid read alone from a multi-grid file keeps its index too).
const nanovdb::FloatGrid* checked_float_grid(const NanoHandle& handle) {
  return reinterpret_cast<const nanovdb::FloatGrid*>(handle.data());
}

// A grid buffer under check: where its nodes may lie, and the error for a corrupt one.
struct GridBytes {
  const fs::path& file;
  const uint8_t* base;
  uint64_t size;
  uint64_t nodes_begin = 0;       // first byte after the root table
  uint32_t nodes[3] = {0, 0, 0};  // leaf, lower, upper nodes found

  [[noreturn]] void corrupt(const std::string& what) const { fail(file, "corrupt grid data: " + what); }
  template <typename T>
  const T* at(uint64_t offset) const {
    return reinterpret_cast<const T*>(base + offset);
  }
  // A child at byte offset `parent + rel` must lie inside [nodes_begin, size - node_size], 32B aligned.
  uint64_t child_off(uint64_t parent, int64_t rel, uint64_t node_size) const {
    const uint64_t c = parent + static_cast<uint64_t>(rel);  // wraps for bad negative offsets
    if (c < nodes_begin || c > size || node_size > size - c || c % 32 != 0)
      corrupt(
          fmt::format("node pointer outside the buffer (offset {} of {})", static_cast<int64_t>(c), size));
    return c;
  }
};

// Size, magic, version, value type and voxel size of the grid header.
void check_grid_header(const GridBytes& b) {
  if (b.size < sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>) + sizeof(RootT))
    b.corrupt("buffer too small");
  const auto* gd = b.at<nanovdb::GridData>(0);
  if (gd->mMagic != NANOVDB_MAGIC_NUMBER) b.corrupt("bad magic number");
  if (gd->mGridSize != b.size)
    b.corrupt(fmt::format("grid size {} != buffer size {}", gd->mGridSize, b.size));
  if (gd->mVersion.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
    b.corrupt(fmt::format("grid version {}", version_string(gd->mVersion)));
  if (gd->mGridType != nanovdb::GridType::Float)
    fail(b.file, fmt::format("grid is not a float grid (type {})", type_name(gd->mGridType)));
  for (int a = 0; a < 3; ++a)
    if (!(gd->mVoxelSize[a] > 0 && std::isfinite(gd->mVoxelSize[a]))) b.corrupt("bad voxel size");
}

// The root node's offset (returned) and table; sets b.nodes_begin.
uint64_t check_root(GridBytes& b, uint64_t tree_off) {
  const auto* td = b.at<nanovdb::TreeData<3>>(tree_off);
  const uint64_t root_off = tree_off + td->mNodeOffset[3];
  if (td->mNodeOffset[3] > b.size || root_off % 32 != 0 || root_off > b.size - sizeof(RootT))
    b.corrupt("bad root offset");
  const auto* root = b.at<typename RootT::DataType>(root_off);
  if (root->mTableSize > (b.size - root_off - sizeof(RootT)) / sizeof(typename RootT::Tile))
    b.corrupt("root table overruns the buffer");
  b.nodes_begin = root_off + sizeof(RootT) + root->mTableSize * sizeof(typename RootT::Tile);
  return root_off;
}

void check_lower(GridBytes& b, uint64_t off1) {
  const auto* lo = b.at<typename LowerT::DataType>(off1);
  b.nodes[1]++;
  for (uint32_t n1 = 0; n1 < 4096; ++n1) {
    if (!lo->mChildMask.isOn(n1)) continue;
    b.child_off(off1, lo->mTable[n1].child, sizeof(LeafT));
    b.nodes[0]++;
  }
}

void check_upper(GridBytes& b, uint64_t off2) {
  const auto* up = b.at<typename UpperT::DataType>(off2);
  b.nodes[2]++;
  for (uint32_t n2 = 0; n2 < 32768; ++n2) {
    if (!up->mChildMask.isOn(n2)) continue;
    check_lower(b, b.child_off(off2, up->mTable[n2].child, sizeof(LowerT)));
  }
}

// Every root tile's origin and every child pointer, depth first; counts the nodes.
void check_tree_nodes(GridBytes& b, uint64_t root_off) {
  const auto* root = b.at<typename RootT::DataType>(root_off);
  for (uint32_t t = 0; t < root->mTableSize; ++t) {
    const auto* tile = root->tile(t);
    const Coord o2 = tile->origin();
    // Node origins are derived from this one by adding offsets: keep every voxel of the 4096^3 node
    // representable (a corrupt key near INT_MAX would overflow in Coord arithmetic).
    for (int a = 0; a < 3; ++a)
      if (o2[a] < -detail::kMaxIndexCoord || o2[a] > detail::kMaxIndexCoord - 4096)
        b.corrupt("root tile origin out of range");
    if (tile->isChild()) check_upper(b, b.child_off(root_off, tile->child, sizeof(UpperT)));
  }
}

// The node manager (used by the full checksum) trusts the tree's node counts and first-node offsets,
// and takes the address of every level's first node, even of a level without nodes (a pointer far
// past the buffer is undefined behaviour before anything reads it).
void check_node_arrays(const GridBytes& b, uint64_t tree_off) {
  const auto* td = b.at<nanovdb::TreeData<3>>(tree_off);
  const bool breadth_first = b.at<nanovdb::FloatGrid>(0)->isBreadthFirst();
  for (int l = 0; l < 3; ++l) {
    if (td->mNodeCount[l] != b.nodes[l]) b.corrupt(fmt::format("node count mismatch at level {}", l));
    if (td->mNodeOffset[l] > b.size) b.corrupt(fmt::format("node array at level {} lies past the buffer", l));
    const uint64_t node_size = l == 0 ? sizeof(LeafT) : l == 1 ? sizeof(LowerT) : sizeof(UpperT);
    if (b.nodes[l] > 0 && breadth_first) {
      const uint64_t first = tree_off + td->mNodeOffset[l];
      if (td->mNodeOffset[l] > b.size || first < b.nodes_begin || b.nodes[l] > (b.size - first) / node_size)
        b.corrupt(fmt::format("node array at level {} overruns the buffer", l));
    }
  }
}

// A long grid name: nanovdb's gridName() follows its blind metadata (offset and count from the file)
// without checks. (A short name need not be NUL-terminated either; DensityGrid reads it with strnlen.)
void check_long_name(const GridBytes& b) {
  const auto* gd = b.at<nanovdb::GridData>(0);
  if (!(gd->mFlags & static_cast<uint32_t>(nanovdb::GridFlags::HasLongGridName))) return;
  using Meta = nanovdb::GridBlindMetaData;
  const uint32_t count = gd->mBlindMetadataCount;
  const int64_t meta_rel = gd->mBlindMetadataOffset;
  if (count == 0 || meta_rel < 0 || static_cast<uint64_t>(meta_rel) > b.size ||
      count > (b.size - static_cast<uint64_t>(meta_rel)) / sizeof(Meta))
    b.corrupt("blind metadata outside the buffer");
  const uint64_t meta_off = static_cast<uint64_t>(meta_rel) + (count - 1) * sizeof(Meta);
  const auto* meta = b.at<Meta>(meta_off);
  const uint64_t name_off = meta_off + static_cast<uint64_t>(meta->mByteOffset);  // wraps if negative
  if (meta->mDataClass != nanovdb::GridBlindDataClass::GridName || name_off >= b.size)
    b.corrupt("long grid name outside the buffer");
  const char* name = b.at<char>(name_off);
  if (strnlen(name, static_cast<size_t>(b.size - name_off)) == b.size - name_off)
    b.corrupt("long grid name is not terminated");
}

// Checks a grid read from a file before anything follows its pointers: the header, the tree, the root
// table and every child pointer (inside the buffer, 32-byte aligned, with room for the node), the node
// arrays, the name, and the map (index -> world -> index must round-trip).
void check_grid_structure(const fs::path& file, const NanoHandle& handle) {
  GridBytes b{file, handle.data(), handle.size()};
  check_grid_header(b);
  const uint64_t tree_off = sizeof(nanovdb::GridData);
  const uint64_t root_off = check_root(b, tree_off);
  check_tree_nodes(b, root_off);
  check_node_arrays(b, tree_off);
  check_long_name(b);
  const auto& grid = *checked_float_grid(handle);
  const nanovdb::Vec3d p(1.5, -2.25, 3.75), q = grid.worldToIndex(grid.indexToWorld(p));
  if (!((q - p).length() < 1e-6)) b.corrupt("singular or non-finite index-to-world map");
}

// ---- loading ----------------------------------------------------------------------------------------

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
      list +=
          fmt::format("{}\"{}\" ({})", list.empty() ? "" : ", ", e.meta.gridName, type_name(e.meta.gridType));
    if (chosen != nullptr)
      fail(file,
           fmt::format("grid \"{}\" is of type {}, not float", grid_name, type_name(chosen->meta.gridType)));
    if (grid_name.empty()) fail(file, "no float grid in the file; it holds " + list);
    fail(file, fmt::format("no grid named \"{}\"; the file holds {}", grid_name, list));
  }
  return read_nvdb_grid(file, in, *chosen);
}

}  // namespace

DensityGrid load_density_grid(const fs::path& file, const std::string& grid_name) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const FileKind kind = detect_kind(file);
  NanoHandle handle = kind == FileKind::OpenVDB ? detail::load_openvdb_float_grid(file, grid_name)
                                                : open_nvdb_grid(file, grid_name);
  const auto t1 = Clock::now();
  check_grid_structure(file, handle);
  // Only after the structural check: the checksum reads the root table and every node through the
  // grid's own sizes and offsets (a corrupt root table size read past the buffer; see
  // tests/io/fuzz_regression_test.cpp).
  if (kind == FileKind::NanoVDB &&
      !nanovdb::validateChecksum(*checked_float_grid(handle), nanovdb::ChecksumMode::Full))
    fail(file, "corrupt grid data: checksum mismatch");
  const double read_seconds = std::chrono::duration<double>(t1 - t0).count();
  const double check_seconds = std::chrono::duration<double>(Clock::now() - t1).count();
  return DensityGrid::from_nanovdb(std::move(handle), file.string(), read_seconds, check_seconds);
}

std::array<DensityGrid, 3> load_vec3_grid(const fs::path& file, const std::string& grid_name) {
  if (detect_kind(file) != FileKind::OpenVDB)
    fail(file, fmt::format("grid \"{}\": vec3 grids are read from OpenVDB (.vdb) files only", grid_name));
  auto handles = detail::load_openvdb_vec3_grid(file, grid_name);
  auto component = [&](int c) {
    check_grid_structure(file, handles[c]);
    return DensityGrid::from_nanovdb(std::move(handles[c]),
                                     fmt::format("{} ({}.{})", file.string(), grid_name, "xyz"[c]));
  };
  return {component(0), component(1), component(2)};
}

// ---- inspect --------------------------------------------------------------------------------------

namespace {

const char* class_name(nanovdb::GridClass c) {
  static const char* names[] = {"unknown",    "level set", "fog volume",   "staggered", "point index",
                                "point data", "topology",  "voxel volume", "index grid"};
  const auto i = static_cast<uint32_t>(c);
  return i < std::size(names) ? names[i] : "invalid";
}

// What the file's metadata says about a grid (for float grids, recounted from the data below).
GridInfo grid_info_from_meta(const nanovdb::io::GridMetaData& m) {
  GridInfo gi;
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
  return gi;
}

// Float grids: read them and recount from the data itself.
void recount_float_grid(const fs::path& file, FileReader& in, const NvdbEntry& e, GridInfo& gi) {
  const NanoHandle h = read_nvdb_grid(file, in, e);
  check_grid_structure(file, h);
  const auto* grid = checked_float_grid(h);
  const GridSummary w = summarize_float_grid(*grid);
  gi.active_voxels = w.active_voxels;
  gi.tiles = w.tiles;
  gi.empty = w.active_voxels == 0;
  gi.world_bounds = Bounds{};
  if (gi.empty) return;
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

std::vector<GridInfo> inspect_nvdb_file(const fs::path& file) {
  FileReader in(file);
  const auto entries = parse_nvdb(file, in);
  std::vector<GridInfo> out;
  for (const auto& e : entries) {
    GridInfo gi = grid_info_from_meta(e.meta);
    if (e.meta.gridType == nanovdb::GridType::Float) recount_float_grid(file, in, e, gi);
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
