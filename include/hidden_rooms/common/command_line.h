#pragma once

#include <functional>
#include <string>

#include <boost/program_options.hpp>

namespace hidden_rooms::common {

// Exit codes of the package's command-line tools.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;   // an unexpected failure (a bug, out of memory, ...)
constexpr int kExitBadInput = 2;  // unusable input or command line: the message says which and why

// Runs a tool's body and turns exceptions into a one-line message on stderr ("TOOL: error: ...", control
// characters shown as \xNN) and an exit code: InputError and command-line errors -> kExitBadInput, anything else
// -> kExitFailure.
int runTool(const std::string& tool_name, const std::function<int()>& body);

// Parses argv with `options` (and `positional`, if any). Prints `usage` and the options and returns false for
// --help; throws InputError for an unknown or malformed option.
bool parseCommandLine(int argc, char** argv, const std::string& usage,
                      const boost::program_options::options_description& options,
                      const boost::program_options::positional_options_description& positional,
                      boost::program_options::variables_map* values);

}  // namespace hidden_rooms::common
