#include "fuzz_entries.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/map3d/octomap_io.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms::fuzz {

namespace {

std::string text(const uint8_t* data, size_t size) { return std::string(reinterpret_cast<const char*>(data), size); }

// A file named `name` in a folder of this process, holding `bytes`; for the readers that take paths.
std::string scratchFile(const std::string& name, const std::string& bytes) {
  static const std::filesystem::path dir = [] {
    const auto path = std::filesystem::temp_directory_path() / ("hidden_rooms_fuzz_" + std::to_string(getpid()));
    std::filesystem::create_directories(path);
    return path;
  }();
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  return path;
}

template <typename Read>
void refusingOnlyWithInputError(Read read) {
  try {
    read();
  } catch (const common::InputError&) {
  }
}

}  // namespace

void environmentXml(const uint8_t* data, size_t size) {
  refusingOnlyWithInputError([&] { world::parseEnvironment(text(data, size), "fuzz.xml"); });
}

void mapYaml(const uint8_t* data, size_t size) {
  const std::string bytes = text(data, size);
  const size_t split = bytes.find('\0');
  const std::string yaml = bytes.substr(0, split);
  scratchFile("map.img", split == std::string::npos ? std::string() : bytes.substr(split + 1));
  const std::string path = scratchFile("map.yaml", yaml);
  refusingOnlyWithInputError([&] { common::loadMap(path); });
}

void image(const uint8_t* data, size_t size) {
  const std::string path = scratchFile("image.bin", text(data, size));
  refusingOnlyWithInputError([&] { common::readImage(path); });
}

void doorsYaml(const uint8_t* data, size_t size) {
  refusingOnlyWithInputError([&] { common::parseDoors(text(data, size), "fuzz_doors.yaml"); });
}

void parameterFile(const uint8_t* data, size_t size) {
  const std::string path = scratchFile("params.yaml", text(data, size));
  refusingOnlyWithInputError([&] {
    prediction::resolveParameters(*prediction::makeRoomPredictor("default"), common::loadParameterFile(path));
  });
}

void poseLog(const uint8_t* data, size_t size) {
  refusingOnlyWithInputError([&] { common::parsePoseLog(text(data, size), "fuzz.log"); });
}

void octomap(const uint8_t* data, size_t size) {
  if (size == 0) return;
  const std::string path = scratchFile(data[0] % 2 ? "tree.ot" : "tree.bt", text(data + 1, size - 1));
  refusingOnlyWithInputError([&] { map3d::sliceOctomap(path, map3d::SliceOptions()); });
}

const std::vector<Target>& targets() {
  static const std::vector<Target> all{{"environment_xml", environmentXml}, {"map_yaml", mapYaml},
                                       {"image", image},                    {"doors_yaml", doorsYaml},
                                       {"parameter_file", parameterFile},   {"pose_log", poseLog},
                                       {"octomap", octomap}};
  return all;
}

}  // namespace hidden_rooms::fuzz
