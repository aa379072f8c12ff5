#include "hidden_rooms/segmentation/room_types.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/betweenness_centrality.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ml.hpp>

#include "hidden_rooms/common/embedded_file.h"
#include "hidden_rooms/common/input_error.h"

// The shipped model, built into the library (CMake sets HIDDEN_ROOMS_ROOM_TYPES_MODEL to its path).
HIDDEN_ROOMS_EMBED_FILE(hidden_rooms_room_types_model, HIDDEN_ROOMS_ROOM_TYPES_MODEL);

namespace hidden_rooms::segmentation {

namespace {

// Per room: how many rooms lose their connection to the largest part of the graph without it (a hub's rooms).
std::vector<int> roomsBehind(const std::vector<std::set<int>>& neighbours) {
  const int count = static_cast<int>(neighbours.size());
  std::vector<int> behind(count, 0);
  const auto largestComponent = [&](int removed) {
    std::vector<int> component(count, -1);
    std::vector<int> sizes;
    for (int start = 0; start < count; ++start) {
      if (start == removed || component[start] >= 0) continue;
      std::vector<int> stack = {start};
      component[start] = static_cast<int>(sizes.size());
      int size = 0;
      while (!stack.empty()) {
        const int room = stack.back();
        stack.pop_back();
        ++size;
        for (const int other : neighbours[room])
          if (other != removed && component[other] < 0) {
            component[other] = component[start];
            stack.push_back(other);
          }
      }
      sizes.push_back(size);
    }
    return sizes.empty() ? 0 : *std::max_element(sizes.begin(), sizes.end());
  };
  const int whole = largestComponent(-1);
  for (int room = 0; room < count; ++room) behind[room] = std::max(0, whole - 1 - largestComponent(room));
  return behind;
}

// Per room: over all pairs of other rooms, the mean share of their shortest paths that pass through it
// (betweenness centrality by Brandes's algorithm, Boost.Graph's; in [0, 1]; rooms in different parts of the graph
// have no path). Corridors carry the paths.
std::vector<double> betweenness(const std::vector<std::set<int>>& neighbours) {
  using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS>;
  const int count = static_cast<int>(neighbours.size());
  Graph graph(count);
  for (int room = 0; room < count; ++room)
    for (const int other : neighbours[room])
      if (room < other) boost::add_edge(room, other, graph);
  std::vector<double> centrality(count, 0.0);
  const auto map = boost::make_iterator_property_map(centrality.begin(), boost::get(boost::vertex_index, graph));
  boost::brandes_betweenness_centrality(graph, boost::centrality_map(map));
  // Boost's relative form divides by the (count - 1)(count - 2) / 2 pairs of other rooms, none below three rooms.
  if (count > 2) boost::relative_betweenness_centrality(graph, map);
  return centrality;
}

double outlineLength(const common::Polygon& outline) {
  double length = 0.0;
  for (size_t i = 0; i < outline.size(); ++i) length += (outline[(i + 1) % outline.size()] - outline[i]).norm();
  return length;
}

}  // namespace

const std::vector<std::string>& roomTypeNames() {
  static const std::vector<std::string> names = {"corridor", "office", "classroom", "washroom",
                                                 "storage",  "hall",   "stairs"};
  return names;
}

std::string roomTypeOfLabel(const std::string& label) {
  static const std::map<std::string, std::string> types = {
      {"CORRIDOR", "corridor"},
      {"OFFICE", "office"},          {"SHARED OFFICE", "office"},      {"EXECUTIVE OFFICE", "office"},
      {"SMALL ADMINISTRATIVE", "office"}, {"MEDIUM ADMINISTRATIVE", "office"}, {"BIG ADMINISTRATIVE", "office"},
      {"CUBICULE", "office"},        {"RECEPTION", "office"},
      {"CLASSROOM", "classroom"},    {"LAB", "classroom"},             {"LIBRARY", "classroom"},
      {"CONFERENCE", "classroom"},   {"CONFERENCE ROOM", "classroom"}, {"CONFERENCE HALL", "classroom"},
      {"WASHROOM", "washroom"},      {"BATHROOM", "washroom"},
      {"CLOSET", "storage"},         {"SMALL", "storage"},             {"MEDIUM", "storage"},
      {"MEDIUM SERVICE", "storage"}, {"BIG SERVICE", "storage"},       {"COLLECTIVE SERVICE ROOM", "storage"},
      {"KITCHEN", "storage"},
      {"HALL", "hall"},              {"LOBBY", "hall"},                {"ENTRANCE", "hall"},
      {"OPENSPACE", "hall"},         {"CANTEEN", "hall"},              {"CAFETERIA", "hall"},
      {"GYM", "hall"},               {"CONVENIENCE STORE", "hall"},
      {"STAIRS", "stairs"},          {"ELEVATOR", "stairs"},
  };
  const auto found = types.find(label);
  return found == types.end() ? "" : found->second;
}

RoomKind roomKindOfLabel(const std::string& label) {
  return roomTypeOfLabel(label) == "corridor" ? RoomKind::kCorridor : RoomKind::kRoom;
}

const std::vector<std::string>& roomFeatureNames() {
  static const std::vector<std::string> names = {
      "area",        "width",       "elongation",  "width_uniformity", "long_side",       "short_side",
      "aspect",      "rectangularity", "compactness", "passages",      "neighbours",      "relative_area",
      "area_rank",   "largest_neighbour_ratio", "dead_end_neighbours", "passage_share",
      "neighbour_elongation", "neighbour_degree", "rooms_behind", "betweenness"};
  return names;
}

cv::Mat1f roomFeatures(const SegmentedFloor& floor) {
  const size_t count = floor.rooms.size();
  cv::Mat1f features(static_cast<int>(count), static_cast<int>(roomFeatureNames().size()), 0.0f);
  if (count == 0) return features;
  std::vector<int> passages(count, 0);
  std::vector<double> passage_width(count, 0.0);
  std::vector<std::set<int>> neighbours(count);
  for (const Passage& passage : floor.passages) {
    for (const int label : {passage.room_a, passage.room_b})
      if (label != 0) {
        ++passages[label - 1];
        passage_width[label - 1] += passage.width;
      }
    if (passage.room_a != 0 && passage.room_b != 0) {
      neighbours[passage.room_a - 1].insert(passage.room_b - 1);
      neighbours[passage.room_b - 1].insert(passage.room_a - 1);
    }
  }
  std::vector<double> areas, elongations;
  for (const Room& room : floor.rooms) {
    areas.push_back(room.area);
    elongations.push_back(room.width > 0.0 ? room.area / (room.width * room.width) : 0.0);
  }
  const std::vector<int> behind = roomsBehind(neighbours);
  const std::vector<double> central = betweenness(neighbours);
  std::vector<double> sorted = areas;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (size_t i = 0; i < count; ++i) {
    const Room& room = floor.rooms[i];
    std::vector<cv::Point2f> outline;
    for (const common::Point2& vertex : room.outline) outline.emplace_back(vertex.x(), vertex.y());
    const cv::RotatedRect box = outline.size() >= 3 ? cv::minAreaRect(outline) : cv::RotatedRect();
    const double long_side = std::max(box.size.width, box.size.height);
    const double short_side = std::min(box.size.width, box.size.height);
    double largest_neighbour = 0.0, neighbour_elongation = 0.0, neighbour_degree = 0.0;
    int dead_ends = 0;
    for (const int other : neighbours[i]) {
      largest_neighbour = std::max(largest_neighbour, areas[other]);
      neighbour_elongation = std::max(neighbour_elongation, elongations[other]);
      neighbour_degree += static_cast<double>(neighbours[other].size()) / neighbours[i].size();
      dead_ends += passages[other] == 1;
    }
    const double perimeter = outlineLength(room.outline);
    const double rank = static_cast<double>(std::lower_bound(sorted.begin(), sorted.end(), room.area) - sorted.begin());
    const std::vector<double> values = {
        room.area,
        room.width,
        room.width > 0.0 ? room.area / (room.width * room.width) : 0.0,
        room.width > 0.0 ? room.mean_width / room.width : 0.0,
        long_side,
        short_side,
        short_side > 0.0 ? long_side / short_side : 0.0,
        long_side * short_side > 0.0 ? room.area / (long_side * short_side) : 0.0,
        room.area > 0.0 ? perimeter / std::sqrt(room.area) : 0.0,
        static_cast<double>(passages[i]),
        static_cast<double>(neighbours[i].size()),
        median > 0.0 ? room.area / median : 0.0,
        count > 1 ? rank / (count - 1) : 0.5,
        room.area > 0.0 ? largest_neighbour / room.area : 0.0,
        static_cast<double>(dead_ends),
        perimeter > 0.0 ? passage_width[i] / perimeter : 0.0,
        neighbour_elongation,
        neighbour_degree,
        static_cast<double>(behind[i]),
        central[i],
    };
    for (size_t j = 0; j < values.size(); ++j) features(static_cast<int>(i), static_cast<int>(j)) = static_cast<float>(values[j]);
  }
  return features;
}

RoomTypeClassifier::RoomTypeClassifier(cv::Ptr<cv::ml::RTrees> forest) : forest_(std::move(forest)) {}

const RoomTypeClassifier& RoomTypeClassifier::shipped() {
  static const RoomTypeClassifier classifier = fromText(
      std::string(hidden_rooms_room_types_model, hidden_rooms_room_types_model_end), "models/room_types.yml");
  return classifier;
}

RoomTypeClassifier RoomTypeClassifier::fromText(const std::string& model_text, const std::string& source_name) {
  cv::Ptr<cv::ml::RTrees> forest;
  try {
    cv::FileStorage storage(model_text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    forest = cv::ml::RTrees::create();
    forest->read(storage.getFirstTopLevelNode());
  } catch (const cv::Exception& error) {
    throw common::InputError(source_name, std::string("is not a room type model: ") + error.what());
  }
  if (!forest->isTrained() || forest->getVarCount() != static_cast<int>(roomFeatureNames().size()))
    throw common::InputError(source_name, "is not a room type model of " +
                                              std::to_string(roomFeatureNames().size()) + " features");
  return RoomTypeClassifier(forest);
}

RoomTypeClassifier RoomTypeClassifier::train(const cv::Mat1f& features, const std::vector<int>& types, uint64_t seed) {
  cv::theRNG().state = seed;  // ml::RTrees draws from the thread's generator
  cv::Ptr<cv::ml::RTrees> forest = cv::ml::RTrees::create();
  forest->setMaxDepth(8);
  forest->setMinSampleCount(5);
  forest->setCalculateVarImportance(false);
  forest->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER, 50, 0.0));
  forest->train(cv::ml::TrainData::create(features, cv::ml::ROW_SAMPLE, cv::Mat(types, true)));
  return RoomTypeClassifier(forest);
}

std::vector<int> RoomTypeClassifier::classify(const cv::Mat1f& features) const {
  std::vector<int> types;
  if (features.empty()) return types;
  // A room is a corridor when most trees say so, else of the room type with most votes: a plurality over the
  // seven types would call it a corridor whenever the room votes split among the six room types.
  cv::Mat votes;  // a header row of class labels, then a row of vote counts per sample
  forest_->getVotes(features, votes, 0);
  const int corridor = 0;
  for (int row = 1; row < votes.rows; ++row) {
    int corridor_votes = 0, all_votes = 0, room_type = -1, room_type_votes = -1;
    for (int col = 0; col < votes.cols; ++col) {
      const int type = votes.at<int>(0, col), count = votes.at<int>(row, col);
      all_votes += count;
      if (type == corridor) corridor_votes = count;
      else if (count > room_type_votes) room_type_votes = count, room_type = type;
    }
    types.push_back(2 * corridor_votes > all_votes || room_type < 0 ? corridor : room_type);
  }
  return types;
}

std::string RoomTypeClassifier::toText() const {
  cv::FileStorage storage(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  storage << "room_types";
  storage << "{";
  forest_->write(storage);
  storage << "}";
  return storage.releaseAndGetString();
}

void classifyRooms(const RoomTypeClassifier& classifier, SegmentedFloor* floor) {
  const std::vector<int> types = classifier.classify(roomFeatures(*floor));
  for (size_t i = 0; i < floor->rooms.size(); ++i) {
    Room& room = floor->rooms[i];
    room.type = roomTypeNames().at(static_cast<size_t>(types[i]));
    room.kind = room.type == "corridor" ? RoomKind::kCorridor : RoomKind::kRoom;
  }
}

}  // namespace hidden_rooms::segmentation
