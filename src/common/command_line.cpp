#include "hidden_rooms/common/command_line.h"

#include <cstdio>
#include <exception>
#include <iostream>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

namespace po = boost::program_options;

namespace {

// A message on one line: control characters (a newline quoted from a damaged file, ...) shown as \xNN.
std::string oneLine(const std::string& message) {
  std::string line;
  for (const char c : message) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", static_cast<unsigned char>(c));
      line += escaped;
    } else {
      line += c;
    }
  }
  return line;
}

}  // namespace

int runTool(const std::string& tool_name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& error) {
    std::cerr << tool_name << ": error: " << oneLine(error.what()) << std::endl;
    return kExitBadInput;
  } catch (const std::exception& error) {
    std::cerr << tool_name << ": internal error: " << oneLine(error.what()) << std::endl;
    return kExitFailure;
  }
}

bool parseCommandLine(int argc, char** argv, const std::string& usage, const po::options_description& options,
                      const po::positional_options_description& positional, po::variables_map* values) {
  po::options_description all = options;
  all.add_options()("help,h", "print this help");
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), *values);
    if (values->count("help")) {
      std::cout << usage << "\n\n" << all << std::endl;
      return false;
    }
    po::notify(*values);
  } catch (const po::error& error) {
    throw InputError("command line", std::string(error.what()) + " (see --help)");
  }
  return true;
}

}  // namespace hidden_rooms::common
