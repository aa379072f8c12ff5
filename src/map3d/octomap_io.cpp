#include "hidden_rooms/map3d/octomap_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <memory>
#include <type_traits>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/common/label_image.h"

namespace hidden_rooms::map3d {

namespace {

constexpr int8_t kFreeMax = 19;      // map_saver's thresholds (percent)
constexpr int8_t kOccupiedMin = 65;
constexpr double kEdge = 0.01;      // cells: tolerance of leaf edges against cell edges
constexpr size_t kNodesBetweenPrunings = 4000000;  // about 200 MB of nodes
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
void extrude(const common::OccupancyGrid& map, const cv::Mat1w& labels, double height, Tree* tree) {
  const double resolution = tree->getResolution();
  const int voxels = std::max(1, static_cast<int>(std::ceil(height / resolution - 1e-9)));
  // The room (label) a wall cell belongs to: the label of a room cell among its 8 neighbours.
  cv::Mat1w wall_labels;
  if (!labels.empty()) cv::dilate(labels, wall_labels, cv::Mat());
  size_t prune_at = kNodesBetweenPrunings;
  for (const bool occupied_pass : {false, true}) {
    for (int row = 0; row < map.height(); ++row) {
      // Pruned when it has grown by kNodesBetweenPrunings (columns of one kind merge into few nodes), so memory
      // follows the pruned tree.
      if (tree->size() > prune_at) {
        tree->prune();
        common::checkLimit("octomap export", "the octree's number of nodes after pruning",
                           static_cast<double>(tree->size()), common::kMaxOctreeNodes,
                           ": the map does not compress; lower --height or coarsen --resolution");
        prune_at = tree->size() + kNodesBetweenPrunings;
      }
      for (int col = 0; col < map.width(); ++col) {
        const int8_t value = map.cells(row, col);
        const bool occupied = value >= kOccupiedMin;
        if (value < 0 || (value > kFreeMax && !occupied) || occupied != occupied_pass) continue;
        const common::Point2 centre = map.cellCentre(col, row);
        octomap::OcTreeKey base;
        if (!tree->coordToKeyChecked(octomap::point3d(centre.x(), centre.y(), 0.5 * resolution), base))
          throw common::InputError("octomap export", "the map reaches beyond OctoMap's extent at this resolution");
        forColumn(base, voxels, [&](const octomap::OcTreeKey& key) { tree->updateNode(key, occupied, true); });
        if constexpr (std::is_same_v<Tree, octomap::ColorOcTree>) {
          const int label = labels.empty() ? 0 : (occupied ? wall_labels(row, col) : labels(row, col));
          const cv::Vec3b colour = label > 0 ? common::roomColour(label) : (occupied ? kWallGrey : kFreeGrey);
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
common::OccupancyGrid slice(const Tree& tree, const SliceOptions& options, const std::string& path) {
  if (tree.size() == 0) throw common::InputError(path, "the octree is empty");
  double min_x = 0, min_y = 0, min_z = 0, max_x = 0, max_y = 0, max_z = 0;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const double resolution = options.resolution > 0.0 ? options.resolution : tree.getResolution();
  common::OccupancyGrid grid;
  grid.resolution = resolution;
  grid.origin = common::Point2(min_x, min_y);
  const double columns = std::ceil((max_x - min_x) / resolution - kEdge);
  const double rows = std::ceil((max_y - min_y) / resolution - kEdge);
  if (!std::isfinite(columns * rows)) throw common::InputError(path, "has no finite extent");
  common::checkLimit(path, "the slice's number of cells (" + common::formatNumber(columns) + " x " +
                               common::formatNumber(rows) + " at " + common::formatNumber(resolution) + " m)",
                     columns * rows, common::kMaxMapCells, ": slice it at a coarser resolution");
  const int width = std::max(1, static_cast<int>(columns));
  const int height = std::max(1, static_cast<int>(rows));
  grid.cells = cv::Mat_<int8_t>(height, width, common::OccupancyGrid::kUnknown);
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
          cell = common::OccupancyGrid::kOccupied;
        else if (cell == common::OccupancyGrid::kUnknown)
          cell = common::OccupancyGrid::kFree;
      }
    }
  }
  return grid;
}

constexpr int kTreeDepth = 16;  // OctoMap's levels below the root: nodes at this depth are leaves

// An OctoMap file checked before OctoMap reads it. OctoMap's readers trust the file: they follow the child bits
// past its end (reading garbage) and to any depth, allocating without bound. So the header is parsed here, the
// node structure walked within the file's bytes and OctoMap's depth, the node count compared with the header's,
// and OctoMap reads the stream returned: a header written here followed by exactly the walked bytes.
std::istringstream checkedOctomapStream(const std::string& path, bool binary) {
  std::ifstream file(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) throw common::InputError(path, "cannot be read");
  const std::string first_line = binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
  if (bytes.compare(0, first_line.size(), first_line) != 0)
    throw common::InputError(path, "is not an OctoMap file (the first line is not '" + first_line + "')");

  // Header: "key value" lines and # comments up to a line "data".
  std::string id;
  long long declared_nodes = -1;
  double resolution = 0.0;
  size_t data = std::string::npos;
  size_t line_begin = bytes.find('\n');
  while (line_begin != std::string::npos && ++line_begin < bytes.size()) {
    const size_t line_end = std::min(bytes.find('\n', line_begin), bytes.size());
    std::istringstream fields(bytes.substr(line_begin, line_end - line_begin));
    std::string key;
    fields >> key;
    if (key == "data") {
      data = std::min(line_end + 1, bytes.size());
      break;
    }
    if (key == "id") fields >> id;
    if (key == "size") fields >> declared_nodes;
    if (key == "res") fields >> resolution;
    line_begin = line_end;
  }
  if (data == std::string::npos) throw common::InputError(path, "is not an OctoMap file (no header ending in 'data')");
  if (!(resolution > 0.0) || !std::isfinite(resolution))
    throw common::InputError(path, "declares a resolution that is not positive");
  if (id != "OcTree" && (binary || id != "ColorOcTree"))
    throw common::InputError(path,
                             "holds a tree of type '" + id + "', not an OcTree" + (binary ? "" : " or ColorOcTree"));

  // The nodes, depth first: a .bt spends 2 bytes on each inner node (2 bits per child: 01 occupied leaf, 10 free
  // leaf, 11 inner node); a .ot spends on each node its value (float log-odds, plus r, g, b for a ColorOcTree) and
  // a byte of child bits.
  const size_t node_bytes = binary ? 2 : (id == "ColorOcTree" ? 8 : 5);
  size_t at = data;
  long long nodes = 1;
  const std::function<void(int)> walk = [&](int depth) {
    if (bytes.size() - at < node_bytes)
      throw common::InputError(path, "ends inside its tree (after " + std::to_string(nodes) + " nodes)");
    const auto* node = reinterpret_cast<const unsigned char*>(bytes.data() + at);
    at += node_bytes;
    std::vector<bool> has_children;  // per present child
    for (int child = 0; child < 8; ++child) {
      if (binary) {
        const int code = (node[child / 4] >> (2 * (child % 4))) & 3;
        if (code != 0) has_children.push_back(code == 3);
      } else if ((node[node_bytes - 1] >> child) & 1) {
        has_children.push_back(true);
      }
    }
    if (!has_children.empty() && depth == kTreeDepth)
      throw common::InputError(path, "has nodes deeper than OctoMap's " + std::to_string(kTreeDepth) + " levels");
    nodes += static_cast<long long>(has_children.size());
    for (const bool inner : has_children)
      if (inner) walk(depth + 1);
  };
  walk(0);
  if (nodes != declared_nodes)
    throw common::InputError(
        path, "declares " + std::to_string(declared_nodes) + " nodes but holds " + std::to_string(nodes));

  std::ostringstream header;
  header.precision(17);
  header << first_line << "\nid " << id << "\nsize " << nodes << "\nres " << resolution << "\ndata\n";
  return std::istringstream(header.str() + bytes.substr(data, at - data), std::ios::binary);
}

}  // namespace

void exportOctomap(const common::OccupancyGrid& map, const cv::Mat1w& room_labels, const ExtrusionOptions& options,
                   const std::string& path) {
  if (map.empty()) throw common::InputError("octomap export", "the map is empty");
  if (!(options.height > 0.0) || !std::isfinite(options.height))
    throw common::InputError("octomap export", "the height must be positive");
  if (!(options.resolution >= 0.0) || !std::isfinite(options.resolution))
    throw common::InputError("octomap export", "the resolution must be positive (or 0 for the map's)");
  if (!room_labels.empty() && room_labels.size() != map.cells.size())
    throw common::InputError("octomap export", "the room labels are not the map's size");
  const double resolution = options.resolution > 0.0 ? options.resolution : map.resolution;
  const std::string extension = extensionOf(path);
  if (extension != ".ot" && extension != ".bt")
    throw common::InputError(path, "unknown OctoMap file type '" + extension + "' (use .bt or .ot)");
  // The time it takes: every voxel is visited (about 2 million a second).
  const double voxels_per_column = std::ceil(options.height / resolution - 1e-9);
  const double columns = static_cast<double>(cv::countNonZero(map.cells != common::OccupancyGrid::kUnknown));
  common::checkLimit("octomap export", "the number of voxels (" + common::formatNumber(columns) + " known cells x " +
                         common::formatNumber(voxels_per_column) + " per column)",
                     columns * voxels_per_column, common::kMaxVoxels, ": lower --height or coarsen --resolution");
  octomap::OcTreeKey top;
  if (!octomap::OcTree(resolution).coordToKeyChecked(octomap::point3d(0.0, 0.0, options.height), top))
    throw common::InputError("octomap export", "the height " + common::formatNumber(options.height) +
                                                   " m reaches beyond OctoMap's extent at this resolution");
  common::writeAtomically(path, [&](const std::string& temporary) {
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
    if (!written) throw common::InputError(path, "cannot be written");
  });
}

common::OccupancyGrid sliceOctomap(const std::string& path, const SliceOptions& options) {
  if (!std::isfinite(options.z_min) || !std::isfinite(options.z_max) || options.z_min >= options.z_max)
    throw common::InputError("octomap slice", "the band needs z_min < z_max");
  if (!(options.resolution >= 0.0) || !std::isfinite(options.resolution))
    throw common::InputError("octomap slice", "the resolution must be positive (or 0 for the tree's)");
  if (!common::isFile(path)) throw common::InputError(path, "no such file");
  const std::string extension = extensionOf(path);
  if (extension == ".bt") {
    std::istringstream stream = checkedOctomapStream(path, true);
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(stream)) throw common::InputError(path, "is not a readable binary OctoMap (.bt)");
    return slice(tree, options, path);
  }
  if (extension == ".ot") {
    std::istringstream stream = checkedOctomapStream(path, false);
    std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(stream));
    if (!tree) throw common::InputError(path, "is not a readable OctoMap (.ot)");
    if (const auto* color = dynamic_cast<const octomap::ColorOcTree*>(tree.get())) return slice(*color, options, path);
    if (const auto* plain = dynamic_cast<const octomap::OcTree*>(tree.get())) return slice(*plain, options, path);
    throw common::InputError(path, "holds a " + tree->getTreeType() + ", not an OcTree or ColorOcTree");
  }
  throw common::InputError(path, "unknown OctoMap file type '" + extension + "' (use .bt or .ot)");
}

}  // namespace hidden_rooms::map3d
