// batch_cases ENV.xml --sequence D1,D2,... --methods A,B [--cases K,...] [options]: the cases of one batch of the
// thesis's batch analysis (docs/method.md#batch-analysis), all methods in one process. Case k closes the first k
// doors of the sequence (door numbers, closing order), erases the rooms behind them, runs every method and scores it;
// one JSON line per case goes to stdout as soon as it is done. `batch_cases ENV.xml --info` prints the environment's
// closable doors. scripts/batch_analysis drives it.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/evaluation/batch_case.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

std::vector<int> parseNumbers(const std::string& text, const std::string& option) {
  std::vector<int> numbers;
  for (const std::string& item : common::splitList(text)) {
    if (item.empty()) continue;
    size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || value < 1) throw common::InputError(option, "'" + item + "' is not a positive integer");
    numbers.push_back(value);
  }
  return numbers;
}

std::string jsonString(const std::string& text) {
  std::ostringstream out;
  out << '"';
  for (const char c : text) {
    if (c == '"' || c == '\\') out << '\\' << c;
    else if (static_cast<unsigned char>(c) < 0x20)
      out << "\\u" << std::hex << std::setw(4) << std::setfill('0') << int(c) << std::dec;
    else out << c;
  }
  out << '"';
  return out.str();
}

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

template <typename T>
std::string jsonList(const std::vector<T>& values) {
  std::string text = "[";
  for (size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + jsonNumber(values[i]);
  return text + "]";
}

void printInfo(const std::string& path, const world::Environment& environment) {
  std::vector<int> closable;
  for (int index : world::closableDoors(environment)) closable.push_back(environment.doors[index].number);
  double free_area = 0.0;
  for (const world::Space& space : environment.spaces) free_area += common::area(space.outline);
  std::cout << "{\"environment\": " << jsonString(path) << ", \"spaces\": " << environment.spaces.size()
            << ", \"doors\": " << environment.doors.size() << ", \"closable\": " << jsonList(closable)
            << ", \"floor_area\": " << jsonNumber(free_area) << "}" << std::endl;
}

int run(int argc, char** argv) {
  po::options_description options("Options");
  world::RenderOptions render_options;
  std::string environment_path, sequence_text, cases_text, methods_text, params_path, map_path, doors_in_map_path,
      write_dir;
  bool info = false;
  options.add_options()
      ("environment", po::value(&environment_path)->required(), "environment XML (thesis schema)")
      ("info", po::bool_switch(&info), "print the environment's closable doors (JSON) and exit (after checking "
                                        "--methods and --params)")
      ("sequence", po::value(&sequence_text), "door numbers in closing order, comma-separated")
      ("cases", po::value(&cases_text), "numbers of closed doors to run, comma-separated (default: 1..length)")
      ("methods", po::value(&methods_text), "prediction methods, comma-separated")
      ("params", po::value(&params_path), "parameter overrides: flat YAML of name: number")
      ("map", po::value(&map_path), "complete map (map_server yaml) instead of the rendering")
      ("doors-in-map", po::value(&doors_in_map_path), "with --map: every door's position in the map (doors.yaml)")
      ("write-cases", po::value(&write_dir), "also write each case's input: DIR/K_doors/{map.yaml,map.pgm,"
                                               "doors.yaml,true_rooms.png}")
      ("resolution", po::value(&render_options.resolution)->default_value(0.05), "metres per cell")
      ("door-width", po::value(&render_options.door_width)->default_value(0.9), "door width, metres")
      ("margin", po::value(&render_options.margin)->default_value(1.0), "unknown border, metres");
  po::positional_options_description positional;
  positional.add("environment", 1);
  std::string methods_known;
  for (const std::string& name : prediction::roomPredictorNames())
    methods_known += (methods_known.empty() ? "" : ", ") + name;
  po::variables_map values;
  const std::string usage =
      "Usage: batch_cases ENV.xml --sequence D1,D2,... --methods A,B [--cases K,...]\n"
      "                   [--params F.yaml] [--map MAP.yaml --doors-in-map DOORS.yaml]\n"
      "                   [--write-cases DIR]\n"
      "       batch_cases ENV.xml --info [--methods A,B] [--params F.yaml]\n"
      "Methods: " + methods_known + "\n"
      "Case K closes the first K doors of the sequence, erases the rooms behind them, paints\n"
      "the doors as walls, runs every method and scores it against the true rooms; prints one\n"
      "JSON line per case: closed_doors, door_ids, hidden_percent, room_coverage (per door: the true\n"
      "room's area / its free area in the rendering), case_seconds and per method mean_iou, iou_total, seconds,\n"
      "not_placed, problem. Without --methods it only builds (and writes) the cases.";
  if (!common::parseCommandLine(argc, argv, usage, options, positional, &values))
    return common::kExitOk;

  const world::Environment environment = world::loadEnvironment(environment_path);
  world::printRepairs(environment, environment_path, std::cerr);
  std::vector<std::unique_ptr<prediction::RoomPredictor>> methods;
  for (const std::string& name : common::splitList(methods_text))
    if (!name.empty()) methods.push_back(prediction::makeRoomPredictor(name));
  std::map<std::string, double> parameters;
  if (!params_path.empty()) parameters = common::loadParameterFile(params_path);
  try {  // unknown names fail up front
    for (const auto& method : methods) prediction::resolveParameters(*method, parameters);
  } catch (const common::InputError& error) {
    throw common::InputError(params_path.empty() ? error.source() : params_path, error.problem());
  }
  if (info) {
    printInfo(environment_path, environment);
    return common::kExitOk;
  }
  if (map_path.empty() != doors_in_map_path.empty())
    throw common::InputError("command line", "--map and --doors-in-map go together");
  const std::vector<int> sequence = parseNumbers(sequence_text, "--sequence");
  if (sequence.empty()) throw common::InputError("--sequence", "no door to close");
  std::vector<int> cases = parseNumbers(cases_text, "--cases");
  if (cases.empty())
    for (size_t k = 1; k <= sequence.size(); ++k) cases.push_back(static_cast<int>(k));
  for (int k : cases)
    if (k > static_cast<int>(sequence.size()))
      throw common::InputError("--cases",
                               std::to_string(k) + " doors but the sequence has " + std::to_string(sequence.size()));
  std::optional<common::OccupancyGrid> complete_map;
  common::DoorsFile doors_in_map;
  if (!map_path.empty()) {
    complete_map = common::loadMap(map_path);
    doors_in_map = common::loadDoors(doors_in_map_path);
  }

  for (int k : cases) {
    const std::vector<int> closed(sequence.begin(), sequence.begin() + k);
    const evaluation::BatchCase batch_case =
        complete_map ? evaluation::makeBatchCaseFromMap(environment, *complete_map, doors_in_map, closed,
                                                        render_options.door_width)
                     : evaluation::makeBatchCase(environment, closed, render_options);
    if (!write_dir.empty()) {
      const std::filesystem::path dir = std::filesystem::path(write_dir) / (std::to_string(k) + "_doors");
      common::createOutputDirectory(dir.string());
      common::saveMap(batch_case.input.map, (dir / "map").string());
      common::saveDoors(batch_case.input.closed_doors, (dir / "doors.yaml").string());
      common::saveLabelImage(batch_case.input.true_rooms, (dir / "true_rooms.png").string());
    }
    std::ostringstream line;
    line << "{\"closed_doors\": " << k << ", \"door_ids\": " << jsonList(closed)
         << ", \"hidden_percent\": " << jsonNumber(batch_case.hidden_percent)
         << ", \"room_coverage\": " << jsonList(batch_case.room_coverage)
         << ", \"case_seconds\": " << jsonNumber(batch_case.seconds) << ", \"methods\": {";
    for (size_t m = 0; m < methods.size(); ++m) {
      const evaluation::MethodOutcome outcome = evaluation::runMethodOnCase(*methods[m], batch_case, parameters);
      line << (m ? ", " : "") << jsonString(outcome.method)
           << ": {\"mean_iou\": " << jsonNumber(outcome.scores.mean_iou)
           << ", \"iou_total\": " << jsonNumber(outcome.scores.iou_total)
           << ", \"seconds\": " << jsonNumber(outcome.seconds) << ", \"not_placed\": " << outcome.not_placed
           << ", \"iou\": " << jsonList(outcome.scores.iou) << ", \"problem\": " << jsonString(outcome.problem) << "}";
    }
    line << "}}";
    std::cout << line.str() << std::endl;
  }
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("batch_cases", [&] { return run(argc, argv); });
}
