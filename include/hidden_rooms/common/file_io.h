#pragma once

// Reading input files with errors that name the file: InputError(path, "cannot open <what>") when it cannot be
// opened, InputError(path, "malformed YAML: ...") when YAML does not parse. Writing output files atomically.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace hidden_rooms::common {

// Whether `path` is a regular file / a folder; false also when the path cannot be examined (a name too long, a
// component that is a file, no permission), where std::filesystem's one-argument forms throw.
bool isFile(const std::string& path);
bool isFolder(const std::string& path);
// The regular files in `folder` (and its subfolders when `recursive`) whose paths end with `suffix`, sorted.
// Throws InputError when `folder` is not a folder.
std::vector<std::string> listFiles(const std::string& folder, const std::string& suffix, bool recursive);

std::string readTextFile(const std::string& path, const std::string& what);
YAML::Node loadYamlFile(const std::string& path, const std::string& what);
// Reads a parameters file: a flat YAML mapping of parameter names to numbers (config/layout.yaml,
// config/prediction.yaml and config/segmentation.yaml are such files). Throws InputError naming the file and the
// problem.
std::map<std::string, double> loadParameterFile(const std::string& path);

// Writes `path` so that no reader (and no killed run) ever leaves a partial file there: `write` fills a temporary
// file beside it, which then replaces `path` in one rename. When `write` throws or the rename fails, the
// temporary file is removed and the error propagates (InputError naming `path` for the rename). The temporary
// is PATH.partialPID; those of writers that no longer run (killed during a write) are removed first.
void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write);
// The same for a text: InputError(path, "cannot write <what>") when it cannot be written.
void writeTextAtomically(const std::string& path, const std::string& text, const std::string& what);

// Creates an output folder (and its parents); throws InputError naming it when that is impossible.
void createOutputDirectory(const std::string& path);

// A tool's output folder, written all or nothing: the files of a run go to a staging folder inside it
// (OUT/.partialPID) and commit() moves them into OUT, each replacing the previous run's file of that name; an
// OutputFolder destroyed without commit() (an error) removes its staging folder, so OUT keeps what it held (an OUT
// it created is removed). The constructor creates OUT and locks it (flock on the folder itself, held until
// destruction); staging folders of runs that no longer run are removed. Throws InputError naming OUT when it cannot
// be created, when another run holds its lock, and (file()) when an output would replace one of `inputs`.
class OutputFolder {
 public:
  OutputFolder(const std::string& out, const std::vector<std::string>& inputs);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  // Where this run writes its output file `name` (a plain file name) until commit().
  std::string file(const std::string& name) const;
  // The prefix to give saveMap for the map STEM.yaml + STEM`image_extension`, checked like file().
  std::string mapPrefix(const std::string& stem, const std::string& image_extension = ".pgm") const;
  // Moves every staged file into OUT. Checks first that each can replace what OUT holds under its name (not a
  // folder), so that a blocked name leaves OUT as it was.
  void commit();

 private:
  std::string out_;
  std::string staging_;
  std::vector<std::string> inputs_;  // canonical paths
  int lock_fd_ = -1;
  bool created_ = false;  // OUT did not exist before: removed again when nothing was committed
  bool committed_ = false;
};

}  // namespace hidden_rooms::common
