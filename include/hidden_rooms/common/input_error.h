#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace hidden_rooms::common {

// Thrown by every reader and validator of the core library when its input is unusable. The message always
// names the offending file (or "<input>" when there is none) and the problem: "FILE: problem".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& source, const std::string& problem)
      : std::runtime_error(source + ": " + problem), source_(source), problem_(problem) {}

  const std::string& source() const { return source_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string source_;
  std::string problem_;
};

// A number as messages and files show it (printf's %.10g: integers stay integers, "inf" for infinity).
std::string formatNumber(double value);

// The items of a list as inputs write it ("a, b,,c," -> {"a", "b", "", "c", ""}), each without the spaces and tabs
// around it; "" has no item. Callers decide what an empty item means.
std::vector<std::string> splitList(const std::string& text, char separator = ',');

}  // namespace hidden_rooms::common
