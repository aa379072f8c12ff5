#include "hidden_rooms/common/input_limits.h"

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

void checkLimit(const std::string& source, const std::string& what, double value, double limit,
                const std::string& hint) {
  if (value > limit)
    throw InputError(source, what + " is " + formatNumber(value) + ", more than the limit of " + formatNumber(limit) +
                                 hint);
}

}  // namespace hidden_rooms::common
