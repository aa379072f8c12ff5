#include "test_util.h"

#include <fstream>
#include <functional>
#include <thread>
#include <chrono>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

#include <opencv2/imgproc.hpp>

namespace hidden_rooms::testing {


}  // namespace hidden_rooms::testing

namespace hidden_rooms::testing {

int startProcess(const std::vector<std::string>& arguments, const std::string& log_path) {
  std::vector<char*> argv;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log >= 0) {
      dup2(log, STDOUT_FILENO);
      dup2(log, STDERR_FILENO);
      close(log);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

bool killProcess(int pid) {
  int status = 0;
  if (waitpid(pid, &status, WNOHANG) != 0) return false;  // it exited already (and is reaped now)
  kill(pid, SIGKILL);  // a child that exits meanwhile stays a zombie until reaped: its pid is still its own
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int killSpreadOver(const std::function<int()>& start, double seconds, int attempts,
                   const std::function<void(int)>& after_kill) {
  int killed = 0;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const int pid = start();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds * (attempt + 0.5) / attempts));
    killed += killProcess(pid);
    after_kill(attempt);
  }
  return killed;
}

int waitProcess(int pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<std::string> fileNames(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

CommandResult runCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  size_t read = 0;
  while ((read = fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.output.append(buffer, read);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

namespace {

std::string point(int x, int y) {
  return "<point x=\"" + std::to_string(x) + "\" y=\"" + std::to_string(y) + "\"/>";
}

std::string segment(const std::string& id, int x0, int y0, int x1, int y1, const std::string& segment_class,
                    const std::string& status = "") {
  std::string text = "<linesegment id=\"" + id + "\">" + point(x0, y0) + point(x1, y1) + "<class>" +
                     segment_class + "</class><type>EXPLICIT</type><features>NORMAL</features>";
  if (!status.empty()) text += "<status>" + status + "</status>";
  return text + "</linesegment>";
}

std::string portalLink(const std::string& segment_id, const std::string& a, const std::string& b) {
  return "<portal><linesegment>" + segment_id + "</linesegment><class>HORIZONTAL</class><type>EXPLICIT</type>"
         "<features>NORMAL</features><direction>BOTH</direction><target><id>" + a + "</id><id>" + b +
         "</id></target></portal>";
}

std::string space(const std::string& id, const std::string& label, const std::vector<std::pair<int, int>>& outline,
                  const std::string& segments, const std::string& portals) {
  std::string text = "<space id=\"" + id + "\"><labels><type>X</type><label>" + label + "</label></labels>";
  text += "<bounding_polygon>";
  for (const auto& [x, y] : outline) text += point(x, y);
  text += "</bounding_polygon><space_representation>" + segments + "</space_representation><portals>" + portals +
          "</portals></space>";
  return text;
}

}  // namespace

std::string corridorWithTwoRoomsXml(const std::string& door1_status, const std::string& extra_portal) {
  const std::string corridor = space(
      "corridor", "CORRIDOR", {{0, 0}, {0, 40}, {200, 40}, {200, 0}},
      segment("c1", 0, 0, 0, 40, "WALL") + segment("c2", 0, 40, 40, 40, "WALL") +
          segment("door_a", 40, 40, 40, 40, "PORTAL", door1_status) + segment("c3", 40, 40, 140, 40, "WALL") +
          segment("door_b", 140, 40, 140, 40, "PORTAL") + segment("c4", 140, 40, 200, 40, "WALL") +
          segment("c5", 200, 40, 200, 0, "WALL") + segment("c6", 200, 0, 0, 0, "WALL"),
      portalLink("door_a", "corridor", "room_a") + portalLink("door_b", "corridor", "room_b"));
  std::string room_a_segments = segment("a1", 0, 40, 40, 40, "WALL") +
                                segment("door_a", 40, 40, 40, 40, "PORTAL", door1_status) +
                                segment("a2", 40, 40, 80, 40, "WALL") + segment("a3", 80, 40, 80, 120, "WALL") +
                                segment("a4", 80, 120, 0, 120, "WALL") + segment("a5", 0, 120, 0, 40, "WALL");
  if (!extra_portal.empty()) room_a_segments += extra_portal;
  const std::string room_a = space("room_a", "OFFICE", {{0, 40}, {80, 40}, {80, 120}, {0, 120}}, room_a_segments,
                                   portalLink("door_a", "room_a", "corridor"));
  const std::string room_b = space(
      "room_b", "OFFICE", {{80, 40}, {200, 40}, {200, 120}, {80, 120}},
      segment("b1", 80, 40, 140, 40, "WALL") + segment("door_b", 140, 40, 140, 40, "PORTAL") +
          segment("b2", 140, 40, 200, 40, "WALL") + segment("b3", 200, 40, 200, 120, "WALL") +
          segment("b4", 200, 120, 80, 120, "WALL") + segment("b5", 80, 120, 80, 40, "WALL"),
      portalLink("door_b", "room_b", "corridor"));
  return "<?xml version=\"1.0\"?><building id=\"test\"><name>corridor_with_two_rooms</name><scale>"
         "<represented_distance><value>20</value><um>pixel</um></represented_distance>"
         "<real_distance><value>100</value><um>cm</um></real_distance></scale>"
         "<building_type><main_type>OFFICE</main_type></building_type><floor><spaces>" +
         corridor + room_a + room_b + "</spaces></floor></building>";
}

void syntheticHiddenRoomA(common::OccupancyGrid* map, common::DoorsFile* doors, cv::Mat1w* truth) {
  const world::Environment environment = world::parseEnvironment(corridorWithTwoRoomsXml(), "synthetic");
  world::RenderedEnvironment rendered = world::renderEnvironment(environment, {0});
  const cv::Mat1b room_a = rendered.space_labels == 2;
  rendered.map.cells.setTo(common::OccupancyGrid::kUnknown, room_a);
  *map = rendered.map;
  *doors = rendered.closed_doors;
  *truth = cv::Mat1w::zeros(room_a.size());
  truth->setTo(1, room_a);
}

namespace {

// Runs `method` on every valid case of the shared closed-door benchmark; `score` gets the case's folder, request
// and room labels (roomLabels).
void forEachBenchmarkCase(
    const std::string& method,
    const std::function<void(const std::string&, const prediction::PredictionRequest&, const cv::Mat&)>& score) {
  const std::string root = sharedDir() + "/data/closed_door_benchmark";
  std::ifstream csv(root + "/cases.csv");
  std::string line;
  std::getline(csv, line);  // header: env,case,closed_doors_nominal,doors_found,valid,...
  const auto predictor = prediction::makeRoomPredictor(method);
  while (std::getline(csv, line)) {
    std::vector<std::string> fields;
    std::stringstream row(line);
    for (std::string field; std::getline(row, field, ',');) fields.push_back(field);
    if (fields.size() < 5 || fields[4] != "1") continue;
    const std::string dir = root + "/" + fields[0] + "/" + fields[1];
    prediction::PredictionRequest request;
    request.map = common::loadMap(dir + "/map.yaml");
    request.doors = common::loadDoors(dir + "/doors.yaml");
    const prediction::PredictionResult result = predictor->predict(request);
    score(dir, request, prediction::roomLabels(request.map, request.doors, result.rooms));
  }
}

}  // namespace

double benchmarkMeanIou(const std::string& method, int* cases) {
  double total = 0.0;
  int scored = 0;
  forEachBenchmarkCase(method, [&](const std::string& dir, const prediction::PredictionRequest& request,
                                   const cv::Mat& labels) {
    const cv::Mat truth = cv::imread(dir + "/gt_rooms.png", cv::IMREAD_UNCHANGED);
    total += evaluation::scoreRooms(labels, truth, static_cast<int>(request.doors.doors.size())).mean_iou;
    ++scored;
  });
  if (cases != nullptr) *cases = scored;
  return scored > 0 ? total / scored : 0.0;
}

double benchmarkAgreement(const std::string& method, int* rooms) {
  double total = 0.0;
  int compared = 0;
  forEachBenchmarkCase(method, [&](const std::string& dir, const prediction::PredictionRequest& request,
                                   const cv::Mat& labels) {
    const cv::Mat reference = cv::imread(dir + "/reference_rooms.png", cv::IMREAD_UNCHANGED);
    if (reference.empty()) return;
    const int doors = static_cast<int>(request.doors.doors.size());
    const evaluation::RoomScores scores = evaluation::scoreRooms(labels, reference, doors);
    for (int k = 1; k <= doors; ++k) {
      const bool both_empty = cv::countNonZero(labels == k) == 0 && cv::countNonZero(reference == k) == 0;
      total += both_empty ? 1.0 : scores.iou[k - 1];
      ++compared;
    }
  });
  if (rooms != nullptr) *rooms = compared;
  return compared > 0 ? total / compared : 0.0;
}

}  // namespace hidden_rooms::testing
