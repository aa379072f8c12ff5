// render_environment ENV.xml --out DIR [--resolution R] [--closed ID,...|all]: the ground truth of an
// environment as a map_server map, a label image of its spaces, its closed doors and a preview.
#include <iostream>
#include <optional>
#include <set>


#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  po::options_description options("Options");
  world::RenderOptions render_options;
  std::string environment_path, out_dir, closed_spec;
  double wall_thickness = 0.0;
  bool hide_rooms = false;
  options.add_options()
      ("environment", po::value(&environment_path)->required(), "environment XML (thesis schema)")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("resolution", po::value(&render_options.resolution)->default_value(0.05), "metres per cell")
      ("closed", po::value(&closed_spec),
       "doors drawn closed: comma-separated door numbers or ids, 'closable' or 'all'")
      ("hide-closed-rooms", po::bool_switch(&hide_rooms),
       "make the room behind each closed door unknown, as a robot would map it, and write DIR/true_rooms.png")
      ("door-width", po::value(&render_options.door_width)->default_value(0.9), "gap cut at open doors, metres")
      ("wall-thickness", po::value(&wall_thickness),
       "wall thickness, metres (default: the file's <wall_thickness>, else 0.15)")
      ("margin", po::value(&render_options.margin)->default_value(1.0), "unknown border, metres");
  po::positional_options_description positional;
  positional.add("environment", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: render_environment ENV.xml --out DIR [--resolution R] [--closed ID,...|closable|all]\n"
          "                          [--hide-closed-rooms]\n"
          "Writes DIR/map.yaml, DIR/map.pgm, DIR/spaces.png (label = 1 + space index in XML order),\n"
          "DIR/doors.yaml (the closed doors, map frame) and DIR/preview.png; with --hide-closed-rooms\n"
          "also DIR/true_rooms.png (label k = the room behind the k-th closed door).",
          options, positional, &values))
    return common::kExitOk;
  if (values.count("wall-thickness")) render_options.wall_thickness = wall_thickness;

  const world::Environment environment = world::loadEnvironment(environment_path);
  world::printRepairs(environment, environment_path, std::cerr);
  const std::set<int> closed = world::parseDoorSelection(environment, closed_spec, "--closed");
  const world::RenderedEnvironment rendered = world::renderEnvironment(environment, closed, render_options);

  std::optional<world::HiddenRoomsCase> hidden;
  if (hide_rooms) hidden = world::hideClosedRooms(environment, rendered);

  common::OutputFolder out(out_dir, {environment_path});
  common::saveMap(hidden ? hidden->map : rendered.map, out.mapPrefix("map"));
  common::saveLabelImage(rendered.space_labels, out.file("spaces.png"));
  common::saveDoors(rendered.closed_doors, out.file("doors.yaml"));
  if (hidden) common::saveLabelImage(hidden->true_rooms, out.file("true_rooms.png"));
  common::writeImage(out.file("preview.png"), world::renderPreview(environment, rendered));
  out.commit();

  std::cout << environment_path << ": " << environment.spaces.size() << " spaces, " << environment.doors.size()
            << " doors (" << world::closableDoors(environment).size() << " closable), "
            << rendered.closed_doors.doors.size() << " closed; map " << rendered.map.width() << "x"
            << rendered.map.height() << " cells at " << rendered.map.resolution << " m -> " << out_dir << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("render_environment", [&] { return run(argc, argv); });
}
