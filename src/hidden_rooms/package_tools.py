"""Finding and running the package's executables from its Python scripts, and their command lines."""
import argparse
import os

PACKAGE_NAME = "hidden_rooms"
REPO_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


class ToolError(Exception):
    """Unusable arguments or input, or a missing executable (the scripts exit with code 2)."""


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, but a bad command line gives one line, as the C++ tools do: "PROG: error: MESSAGE (see
    --help)" and exit code 2, instead of the whole usage first."""

    def error(self, message):
        self.exit(2, "%s: error: %s (see --help)\n" % (self.prog, message))


def find_binary(name, explicit=None):
    """Path of one of the package's executables: `explicit`, else $CMAKE_PREFIX_PATH's lib/hidden_rooms, else the
    checkout's .ws workspace."""
    if explicit:
        if not (os.path.isfile(explicit) and os.access(explicit, os.X_OK)):
            raise ToolError("--binary %s is not an executable file" % explicit)
        return explicit
    candidates = [os.path.join(prefix, "lib", PACKAGE_NAME, name)
                  for prefix in os.environ.get("CMAKE_PREFIX_PATH", "").split(os.pathsep) if prefix]
    candidates.append(os.path.join(REPO_DIR, ".ws", "devel", "lib", PACKAGE_NAME, name))
    for candidate in candidates:
        if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return candidate
    raise ToolError("%s not found; looked in:\n  %s\nBuild the workspace and source its devel/setup.bash, or "
                    "pass --binary PATH" % (name, "\n  ".join(candidates)))


def tool_error(result, what):
    """The tool's own one-line message (stderr), else its exit code."""
    message = (result.stderr or "").strip().splitlines()
    return message[-1] if message else "%s failed with exit code %d" % (what, result.returncode)
