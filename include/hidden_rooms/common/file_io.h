#pragma once

// Reading input files with errors that name the file: InputError(path, "cannot open <what>") when it cannot be
// opened, InputError(path, "malformed YAML: ...") when YAML does not parse. Writing output files atomically.

#include <functional>
#include <string>

#include <yaml-cpp/yaml.h>

namespace hidden_rooms::common {

std::string readTextFile(const std::string& path, const std::string& what);
YAML::Node loadYamlFile(const std::string& path, const std::string& what);

// Writes `path` so that no reader (and no killed run) ever leaves a partial file there: `write` fills a temporary
// file beside it, which then replaces `path` in one rename. When `write` throws or the rename fails, the
// temporary file is removed and the error propagates (InputError naming `path` for the rename). The temporary
// is PATH.partialPID; those of writers that no longer run (killed during a write) are removed first.
void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write);
// The same for a text: InputError(path, "cannot write <what>") when it cannot be written.
void writeTextAtomically(const std::string& path, const std::string& text, const std::string& what);

// Creates an output folder (and its parents); throws InputError naming it when that is impossible.
void createOutputDirectory(const std::string& path);

}  // namespace hidden_rooms::common
