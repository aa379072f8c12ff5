// Every input kept in test/fuzz/regressions/TARGET/ (crashes the fuzzers found, fixed since, and crafted edge
// cases) goes through its reader again: refused with InputError or read, never a crash (the sanitizer build of
// these tests catches memory errors too).
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "fuzz/fuzz_entries.h"

namespace hidden_rooms {
namespace {

TEST(FuzzRegressions, KeptInputsAreReadOrRefusedCleanly) {
  const std::filesystem::path root = std::filesystem::path(HIDDEN_ROOMS_SOURCE_DIR) / "test" / "fuzz" / "regressions";
  int inputs = 0;
  for (const fuzz::Target& target : fuzz::targets()) {
    const std::filesystem::path dir = root / target.name;
    ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir << " missing";
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      std::ifstream file(entry.path(), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(entry.path().string());
      EXPECT_NO_THROW(target.run(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
      ++inputs;
    }
  }
  EXPECT_GE(inputs, static_cast<int>(fuzz::targets().size()));
}

}  // namespace
}  // namespace hidden_rooms
