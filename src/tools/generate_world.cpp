// generate_world --seed S --size small|medium|large --out F.xml: a procedural office/school floor in the
// thesis's environment XML schema. The same seed and size always give the same file.
#include <cstdint>
#include <iostream>
#include <limits>
#include <string>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/world_generator.h"

namespace po = boost::program_options;

namespace {

int run(int argc, char** argv) {
  po::options_description options("Options");
  long long seed = 0;
  std::string size_text, out_path;
  options.add_options()
      ("seed", po::value(&seed)->required(), "random seed, 0 .. 4294967295")
      ("size", po::value(&size_text)->required(), "size class by closable doors: small (< 10), medium (10..15), "
                                                  "large (>= 16)")
      ("out", po::value(&out_path)->required(), "output environment XML");
  po::variables_map values;
  if (!hidden_rooms::common::parseCommandLine(
          argc, argv,
          "Usage: generate_world --seed S --size small|medium|large --out F.xml\n"
          "Writes a generated floor (corridors with rooms along them) as environment "
          "XML.",
          options, po::positional_options_description(), &values))
    return hidden_rooms::common::kExitOk;
  if (seed < 0 || seed > static_cast<long long>(std::numeric_limits<std::uint32_t>::max()))
    throw hidden_rooms::common::InputError("command line",
                                           "--seed " + std::to_string(seed) + " is out of range (0 .. " +
                                               std::to_string(std::numeric_limits<std::uint32_t>::max()) + ")");
  const hidden_rooms::world::SizeClass size_class = hidden_rooms::world::parseSizeClass(size_text);

  const hidden_rooms::world::Environment environment =
      hidden_rooms::world::generateWorld(static_cast<std::uint32_t>(seed), size_class);
  hidden_rooms::world::saveEnvironment(environment, out_path);
  std::cout << out_path << ": " << hidden_rooms::world::toString(size_class) << " world '" << environment.name << "', "
            << environment.spaces.size() << " spaces, " << environment.doors.size() << " doors ("
            << hidden_rooms::world::closableDoors(environment).size() << " closable)" << std::endl;
  return hidden_rooms::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return hidden_rooms::common::runTool("generate_world", [&] { return run(argc, argv); });
}
