#include "hidden_rooms/common/options.h"

#include <cmath>

namespace hidden_rooms::common {

void requireInRange(const std::string& source, double value, const ParameterRange& range) {
  const bool above_low = range.low_open ? value > range.low : value >= range.low;
  const bool below_high = range.high_open ? value < range.high : value <= range.high;
  if (above_low && below_high && (!range.integer || value == std::floor(value))) return;
  throw InputError(source, std::string("must be ") + (range.integer ? "an integer " : "") + "in " +
                               (range.low_open ? "(" : "[") + formatNumber(range.low) + ", " +
                               formatNumber(range.high) + (range.high_open ? ")" : "]") + ", got " +
                               formatNumber(value));
}

}  // namespace hidden_rooms::common
