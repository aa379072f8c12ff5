#include "hidden_rooms/octomap_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <memory>
#include <type_traits>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include "hidden_rooms/file_io.h"
#include "hidden_rooms/input_error.h"
#include "hidden_rooms/prediction_support.h"

namespace hidden_rooms {

namespace {

constexpr int8_t kFreeMax = 19;      // map_saver's thresholds (percent)
constexpr int8_t kOccupiedMin = 65;
constexpr double kEdge = 0.01;      // cells: tolerance of leaf edges against cell edges
const cv::Vec3b kWallGrey(90, 90, 90);
const cv::Vec3b kFreeGrey(220, 220, 220);

std::string extensionOf(const std::string& path) { return std::filesystem::path(path).extension().string(); }

// Every voxel of the column above (x, y), z in [0, height).
template <typename Visit>
void forColumn(const octomap::OcTreeKey& base, int voxels, Visit visit) {
  octomap::OcTreeKey key = base;
  for (int k = 0; k < voxels; ++k) {
    key[2] = static_cast<octomap::key_type>(base[2] + k);
    visit(key);
  }
}

// Fills `tree` with the extruded map: free columns first, then occupied ones (a coarser voxel holding both
// kinds of cells is occupied); ColorOcTree voxels also get their colour.
template <typename Tree>
void extrude(const OccupancyGrid& map, const cv::Mat1w& labels, double height, Tree* tree) {
  const double resolution = tree->getResolution();
  const int voxels = std::max(1, static_cast<int>(std::ceil(height / resolution - 1e-9)));
  // The room (label) a wall cell belongs to: the label of a room cell among its 8 neighbours.
  cv::Mat1w wall_labels;
  if (!labels.empty()) cv::dilate(labels, wall_labels, cv::Mat());
  for (const bool occupied_pass : {false, true}) {
    for (int row = 0; row < map.height(); ++row) {
      for (int col = 0; col < map.width(); ++col) {
        const int8_t value = map.cells(row, col);
        const bool occupied = value >= kOccupiedMin;
        if (value < 0 || (value > kFreeMax && !occupied) || occupied != occupied_pass) continue;
        const Point2 centre = map.cellCentre(col, row);
        octomap::OcTreeKey base;
        if (!tree->coordToKeyChecked(octomap::point3d(centre.x(), centre.y(), 0.5 * resolution), base))
          throw InputError("octomap export", "the map reaches beyond OctoMap's extent at this resolution");
        forColumn(base, voxels, [&](const octomap::OcTreeKey& key) { tree->updateNode(key, occupied, true); });
        if constexpr (std::is_same_v<Tree, octomap::ColorOcTree>) {
          const int label = labels.empty() ? 0 : (occupied ? wall_labels(row, col) : labels(row, col));
          const cv::Vec3b colour = label > 0 ? roomColour(label) : (occupied ? kWallGrey : kFreeGrey);
          forColumn(base, voxels, [&](const octomap::OcTreeKey& key) {
            tree->setNodeColor(key, colour[2], colour[1], colour[0]);  // roomColour is BGR
          });
        }
      }
    }
  }
  tree->updateInnerOccupancy();
  tree->prune();
}

// Projects the band of `tree` into a grid (see sliceOctomap).
template <typename Tree>
OccupancyGrid slice(const Tree& tree, const SliceOptions& options, const std::string& path) {
  if (tree.size() == 0) throw InputError(path, "the octree is empty");
  double min_x = 0, min_y = 0, min_z = 0, max_x = 0, max_y = 0, max_z = 0;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const double resolution = options.resolution > 0.0 ? options.resolution : tree.getResolution();
  OccupancyGrid grid;
  grid.resolution = resolution;
  grid.origin = Point2(min_x, min_y);
  const int width = std::max(1, static_cast<int>(std::ceil((max_x - min_x) / resolution - kEdge)));
  const int height = std::max(1, static_cast<int>(std::ceil((max_y - min_y) / resolution - kEdge)));
  grid.cells = cv::Mat_<int8_t>(height, width, OccupancyGrid::kUnknown);
  for (auto leaf = tree.begin_leafs(), end = tree.end_leafs(); leaf != end; ++leaf) {
    const double half = 0.5 * leaf.getSize();
    const octomap::point3d centre = leaf.getCoordinate();
    if (centre.z() + half <= options.z_min || centre.z() - half >= options.z_max) continue;
    const bool occupied = tree.isNodeOccupied(*leaf);
    // Cells the leaf covers; OctoMap's coordinates are floats, hence the tolerance of a hundredth of a cell.
    const int col_begin = std::max(0, static_cast<int>(std::floor((centre.x() - half - min_x) / resolution + kEdge)));
    const int col_end = std::min(width, static_cast<int>(std::ceil((centre.x() + half - min_x) / resolution - kEdge)));
    const int y_begin = std::max(0, static_cast<int>(std::floor((centre.y() - half - min_y) / resolution + kEdge)));
    const int y_end = std::min(height, static_cast<int>(std::ceil((centre.y() + half - min_y) / resolution - kEdge)));
    for (int y = y_begin; y < y_end; ++y) {
      for (int col = col_begin; col < col_end; ++col) {
        int8_t& cell = grid.cells(height - 1 - y, col);
        if (occupied)
          cell = OccupancyGrid::kOccupied;
        else if (cell == OccupancyGrid::kUnknown)
          cell = OccupancyGrid::kFree;
      }
    }
  }
  return grid;
}

// Reads the header OctoMap's readers trust ("id", "size", "res" lines up to "data") and refuses what would make
// them allocate for nodes the file cannot hold: a .bt spends 2 bytes on every inner node for its 8 children (at
// most 4.5 nodes per byte) and a .ot more, so a file declaring more than 8 nodes per remaining byte is damaged.
void checkOctomapHeader(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::string line;
  long long declared_nodes = -1;
  double resolution = 0.0;
  bool data = false;
  for (int lines = 0; lines < 100 && std::getline(file, line); ++lines) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "size") fields >> declared_nodes;
    if (key == "res") fields >> resolution;
    if (key == "data") {
      data = true;
      break;
    }
  }
  if (!data) throw InputError(path, "is not an OctoMap file (no header ending in 'data')");
  if (!(resolution > 0.0) || !std::isfinite(resolution))
    throw InputError(path, "declares a resolution that is not positive");
  const std::streamoff header = file.tellg();
  file.seekg(0, std::ios::end);
  const long long remaining = static_cast<long long>(file.tellg() - header);
  if (declared_nodes < 0 || declared_nodes > 8 * remaining)
    throw InputError(path, "declares " + std::to_string(declared_nodes) + " nodes but holds only " +
                               std::to_string(remaining) + " bytes of them");
}

}  // namespace

void exportOctomap(const OccupancyGrid& map, const cv::Mat1w& room_labels, const ExtrusionOptions& options,
                   const std::string& path) {
  if (map.empty()) throw InputError("octomap export", "the map is empty");
  if (!(options.height > 0.0) || !std::isfinite(options.height))
    throw InputError("octomap export", "the height must be positive");
  if (!(options.resolution >= 0.0) || !std::isfinite(options.resolution))
    throw InputError("octomap export", "the resolution must be positive (or 0 for the map's)");
  if (!room_labels.empty() && room_labels.size() != map.cells.size())
    throw InputError("octomap export", "the room labels are not the map's size");
  const double resolution = options.resolution > 0.0 ? options.resolution : map.resolution;
  const std::string extension = extensionOf(path);
  if (extension != ".ot" && extension != ".bt")
    throw InputError(path, "unknown OctoMap file type '" + extension + "' (use .bt or .ot)");
  writeAtomically(path, [&](const std::string& temporary) {
    bool written = false;
    if (extension == ".ot") {
      octomap::ColorOcTree tree(resolution);
      extrude(map, room_labels, options.height, &tree);
      written = tree.write(temporary);
    } else {
      octomap::OcTree tree(resolution);
      extrude(map, room_labels, options.height, &tree);
      written = tree.writeBinary(temporary);
    }
    if (!written) throw InputError(path, "cannot be written");
  });
}

cv::Mat1w roomLabelsFromYaml(const std::string& rooms_yaml, const OccupancyGrid& map) {
  const YAML::Node root = loadYamlFile(rooms_yaml, "rooms file");
  const YAML::Node rooms = root["rooms"];
  if (!rooms || !rooms.IsSequence()) throw InputError(rooms_yaml, "has no 'rooms' list");
  cv::Mat1w labels = cv::Mat1w::zeros(map.height(), map.width());
  for (size_t k = 0; k < rooms.size(); ++k) {
    const YAML::Node room = rooms[k];
    const std::string where = "rooms[" + std::to_string(k) + "]";
    try {
      if (room["placed"] && !room["placed"].as<bool>()) continue;
      const int label = room["label"] ? room["label"].as<int>() : static_cast<int>(k) + 1;
      if (label <= 0 || label > 65535) throw InputError(rooms_yaml, where + ".label is out of range");
      std::vector<cv::Point> polygon;
      for (const YAML::Node& vertex : room["polygon"]) {
        const Point2 point(vertex[0].as<double>(), vertex[1].as<double>());
        if (!point.allFinite()) throw InputError(rooms_yaml, where + " has a non-finite vertex");
        const Point2 image = map.toImage(point);
        polygon.emplace_back(static_cast<int>(std::lround(image.x() - 0.5)),
                             static_cast<int>(std::lround(image.y() - 0.5)));
      }
      if (polygon.size() < 3) throw InputError(rooms_yaml, where + " needs a polygon of at least 3 vertices");
      cv::fillPoly(labels, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(label));
    } catch (const YAML::Exception& error) {
      throw InputError(rooms_yaml, where + " is malformed: " + error.msg);
    }
  }
  return labels;
}

OccupancyGrid sliceOctomap(const std::string& path, const SliceOptions& options) {
  if (!std::isfinite(options.z_min) || !std::isfinite(options.z_max) || options.z_min >= options.z_max)
    throw InputError("octomap slice", "the band needs z_min < z_max");
  if (!(options.resolution >= 0.0) || !std::isfinite(options.resolution))
    throw InputError("octomap slice", "the resolution must be positive (or 0 for the tree's)");
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "no such file");
  const std::string extension = extensionOf(path);
  if (extension == ".bt" || extension == ".ot") checkOctomapHeader(path);
  if (extension == ".bt") {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(path)) throw InputError(path, "is not a readable binary OctoMap (.bt)");
    return slice(tree, options, path);
  }
  if (extension == ".ot") {
    std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(path));
    if (!tree) throw InputError(path, "is not a readable OctoMap (.ot)");
    if (const auto* color = dynamic_cast<const octomap::ColorOcTree*>(tree.get())) return slice(*color, options, path);
    if (const auto* plain = dynamic_cast<const octomap::OcTree*>(tree.get())) return slice(*plain, options, path);
    throw InputError(path, "holds a " + tree->getTreeType() + ", not an OcTree or ColorOcTree");
  }
  throw InputError(path, "unknown OctoMap file type '" + extension + "' (use .bt or .ot)");
}

}  // namespace hidden_rooms
