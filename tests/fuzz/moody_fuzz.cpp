// libFuzzer target: Moody's Union Jack directory. The plate's real files are copied once; each
// input replaces one of them (chosen by its first byte) and the plate is read and assembled.
#include <cstdint>
#include <filesystem>

#include "fuzz_util.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/surface/surface.hpp"

using namespace trueaxis;

namespace {
const char* kFiles[] = {"Config.txt", "NE_SE.txt", "SE_SW.txt", "NE_NW.txt", "NW_SW.txt",
                        "NW_SE.txt",  "NE_SW.txt", "N_S.txt",   "E_W.txt"};
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fs = std::filesystem;
  if (size == 0) return 0;
  const std::string dir = fuzz::scratch_dir() + "/plate";
  static const bool copied = [&] {
    fs::create_directories(dir);
    for (const char* f : kFiles)
      fs::copy_file(fs::path(TRUEAXIS_MOODY_DIR) / f, fs::path(dir) / f,
                    fs::copy_options::overwrite_existing);
    return true;
  }();
  (void)copied;
  const char* file = kFiles[data[0] % 9];
  const fs::path target = fs::path(dir) / file;
  const std::string original = (fs::path(TRUEAXIS_MOODY_DIR) / file).string();
  fuzz::write_input("plate/" + std::string(file), data + 1, size - 1);
  fuzz::expect_only_trueaxis_errors([&] {
    const auto m = io::read_moody(dir);
    surface::moody(m);
    surface::moody(m, true);
  });
  fs::copy_file(original, target, fs::copy_options::overwrite_existing);
  return 0;
}
