// Writes the small volume files behind the fuzz seeds: fuzz/data/tiny.{vdb,nvdb} (volumes that the
// scene seeds name) and fuzz/corpus/vdb/ (the same grid as .vdb and as .nvdb uncompressed, ZIP and
// BLOSC, plus a two-grid file and a checksummed one). The grid: 4x3x2 active voxels with values in
// (0, 2], one negative voxel, under a 0.5 voxel size and a translation.
// Usage: make_seeds DATA_DIR CORPUS_DIR (run by `make fuzz-seeds`; the outputs are committed).
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cstdio>
#include <filesystem>

namespace {

openvdb::FloatGrid::Ptr tiny_grid(const char* name) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName(name);
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto xform = openvdb::math::Transform::createLinearTransform(0.5);
  xform->postTranslate(openvdb::Vec3d(-1.0, -0.75, -0.5));
  grid->setTransform(xform);
  auto acc = grid->getAccessor();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 2; ++k) acc.setValueOn(openvdb::Coord(i, j, k), 0.25f * float(1 + i + j + k));
  acc.setValueOn(openvdb::Coord(5, 1, 1), -0.5f);
  return grid;
}

void write_vdb(const std::filesystem::path& file, const openvdb::GridPtrVec& grids) {
  openvdb::io::File f(file.string());
  f.write(grids);
  f.close();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_seeds DATA_DIR CORPUS_DIR\n");
    return 2;
  }
  openvdb::initialize();
  const std::filesystem::path data = argv[1], corpus = argv[2];
  std::filesystem::create_directories(data);
  std::filesystem::create_directories(corpus);
  using nanovdb::io::Codec;
  const auto grid = tiny_grid("density");
  const auto nano = nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*grid, nanovdb::StatsMode::All,
                                                                nanovdb::ChecksumMode::Disable);
  const auto nano_sum = nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*grid, nanovdb::StatsMode::All,
                                                                    nanovdb::ChecksumMode::Full);
  write_vdb(data / "tiny.vdb", {grid});
  nanovdb::io::writeGrid((data / "tiny.nvdb").string(), nano, Codec::ZIP);

  write_vdb(corpus / "tiny.vdb", {grid});
  auto other = openvdb::Vec3SGrid::create();
  other->setName("velocity");
  other->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  write_vdb(corpus / "two_grids.vdb", {other, tiny_grid("density")});
  nanovdb::io::writeGrid((corpus / "tiny_none.nvdb").string(), nano, Codec::NONE);
  nanovdb::io::writeGrid((corpus / "tiny_checksum.nvdb").string(), nano_sum, Codec::NONE);
  nanovdb::io::writeGrid((corpus / "tiny_zip.nvdb").string(), nano, Codec::ZIP);
  nanovdb::io::writeGrid((corpus / "tiny_blosc.nvdb").string(), nano_sum, Codec::BLOSC);
  return 0;
}
