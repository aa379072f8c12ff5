#pragma once

// Options structs whose fields are doubles, exposed as named parameters (config files, --params, service
// overrides) through one table of {name, member} per struct.

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

template <typename Options>
struct ParameterField {
  const char* name;
  double Options::*field;
};

template <typename Options>
std::vector<std::string> parameterNames(const std::vector<ParameterField<Options>>& fields) {
  std::vector<std::string> names;
  for (const ParameterField<Options>& field : fields) names.push_back(field.name);
  return names;
}

template <typename Options>
std::map<std::string, double> parameterValues(const std::vector<ParameterField<Options>>& fields,
                                              const Options& options) {
  std::map<std::string, double> values;
  for (const ParameterField<Options>& field : fields) values[field.name] = options.*field.field;
  return values;
}

// Sets the fields named in `parameters`; other names are left for other tables.
template <typename Options>
void applyParameterValues(const std::vector<ParameterField<Options>>& fields,
                          const std::map<std::string, double>& parameters, Options* options) {
  for (const ParameterField<Options>& field : fields) {
    const auto found = parameters.find(field.name);
    if (found != parameters.end()) options->*field.field = found->second;
  }
}

// Throws InputError("parameters", ...) naming the first field that is not finite.
template <typename Options>
void requireFiniteParameters(const std::vector<ParameterField<Options>>& fields, const Options& options) {
  for (const ParameterField<Options>& field : fields)
    if (!std::isfinite(options.*field.field))
      throw InputError("parameters", std::string("parameter '") + field.name + "' is not finite");
}

// The valid values of a parameter: an interval whose ends are each open or closed, optionally integers only.
struct ParameterRange {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool low_open = false;
  bool high_open = false;
  bool integer = false;
};

// Throws InputError("parameters", "parameter 'NAME' must be [an integer ]in [LOW, HIGH), got VALUE") when
// `value` is outside `range`.
void requireParameterInRange(const std::string& name, double value, const ParameterRange& range);

}  // namespace hidden_rooms::common
