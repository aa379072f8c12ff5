#include "hidden_rooms/common/input_error.h"

#include <cstdio>

namespace hidden_rooms::common {

std::string formatNumber(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

}  // namespace hidden_rooms::common
