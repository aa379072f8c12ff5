#include "hidden_rooms/prediction/room_predictor.h"

#include <cmath>
#include <functional>
#include <set>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/baselines.h"
#include "hidden_rooms/prediction/default_predictor.h"
#include "hidden_rooms/prediction/structured_predictor.h"
#include "hidden_rooms/prediction/thesis_predictor.h"

namespace hidden_rooms::prediction {

namespace {

using Factory = std::function<std::unique_ptr<RoomPredictor>()>;

const std::map<std::string, Factory>& registry() {
  static const std::map<std::string, Factory> methods{
      {"default", [] { return std::make_unique<DefaultPredictor>(); }},
      {"skewnormal", [] { return std::make_unique<SkewNormalPredictor>(); }},
      {"structured", [] { return std::make_unique<StructuredPredictor>(); }},
      {"thesis", [] { return std::make_unique<ThesisPredictor>(); }},
      {"unstructured", [] { return std::make_unique<UnstructuredPredictor>(); }},
  };
  return methods;
}

// Every parameter name some registered method reads.
const std::set<std::string>& namesReadByAnyMethod() {
  static const std::set<std::string> names = [] {
    std::set<std::string> all;
    for (const auto& [name, factory] : registry())
      for (const auto& [parameter, value] : factory()->defaultParameters()) all.insert(parameter);
    return all;
  }();
  return names;
}

}  // namespace

std::map<std::string, double> resolveParameters(const RoomPredictor& method,
                                                const std::map<std::string, double>& overrides) {
  std::map<std::string, double> parameters = method.defaultParameters();
  for (const auto& [name, value] : overrides) {
    if (!std::isfinite(value)) throw common::InputError("parameters", "parameter '" + name + "' is not finite");
    if (parameters.count(name)) {
      parameters[name] = value;
      continue;
    }
    if (namesReadByAnyMethod().count(name) == 0)
      throw common::InputError("parameters", "unknown parameter '" + name + "' (no prediction method reads it)");
  }
  return parameters;
}

std::vector<std::string> roomPredictorNames() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : registry()) names.push_back(name);
  return names;
}

std::unique_ptr<RoomPredictor> makeRoomPredictor(const std::string& name) {
  const auto found = registry().find(name);
  if (found == registry().end()) {
    std::string known;
    for (const std::string& method : roomPredictorNames()) known += (known.empty() ? "" : ", ") + method;
    throw common::InputError("method", "unknown prediction method '" + name + "' (known: " + known + ")");
  }
  return found->second();
}

}  // namespace hidden_rooms::prediction
