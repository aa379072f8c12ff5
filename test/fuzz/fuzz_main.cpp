// libFuzzer entry of one fuzz target: FUZZ_ENTRY names its function in fuzz_entries.h (set by CMake).
#include "fuzz_entries.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hidden_rooms::fuzz::FUZZ_ENTRY(data, size);
  return 0;
}
