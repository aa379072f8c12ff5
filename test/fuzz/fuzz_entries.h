#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hidden_rooms::fuzz {

// One entry per reader of the core: each feeds `data` to the reader the way a user's file reaches it and
// accepts InputError (the reader's clear refusal); anything else (a crash, a sanitizer report, another
// exception) is a finding. Used by the libFuzzer targets (fuzz_main.cpp) and by the regression test that replays
// the kept inputs (test/fuzz/regressions/TARGET/).
void environmentXml(const uint8_t* data, size_t size);  // parseEnvironment
void mapYaml(const uint8_t* data, size_t size);         // loadMap: "yaml text \0 image bytes" (image: map.img)
void image(const uint8_t* data, size_t size);           // readImage (PNG, PGM, PPM)
void doorsYaml(const uint8_t* data, size_t size);       // parseDoors
void parameterFile(const uint8_t* data, size_t size);   // loadParameterFile + resolveParameters("default")
void poseLog(const uint8_t* data, size_t size);         // parsePoseLog
void octomap(const uint8_t* data, size_t size);         // sliceOctomap: first byte odd = .ot, even = .bt

// The targets by name (fuzz_<name> binaries, regression folders).
struct Target {
  std::string name;
  void (*run)(const uint8_t*, size_t);
};
const std::vector<Target>& targets();

}  // namespace hidden_rooms::fuzz
