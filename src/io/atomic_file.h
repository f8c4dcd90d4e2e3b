// Atomic file output: the writer fills a temporary file beside the target, which is then renamed
// over it. On any failure the temporary file is removed and the target left as it was.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace nimbus {

void atomic_write(const std::filesystem::path& path,
                  const std::function<void(const std::filesystem::path& tmp)>& writer);
// Writes bytes through atomic_write, checking every write and the close.
void atomic_write_bytes(const std::filesystem::path& path, const std::string& bytes);

}  // namespace nimbus
