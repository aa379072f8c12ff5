#pragma once

// The largest inputs the package accepts, checked before any work starts so that no tool or node needs more than
// about 2 GB of memory on any input (the table in docs/file_formats.md#limits, which a test holds to these values).
// Each is several times what a real floor needs: the largest of the 63 shared floor plans renders to 5e6 cells.

#include <string>

namespace hidden_rooms::common {

constexpr double kMaxMapCells = 2.5e7;    // cells of a map, pixels of an image: 5000 x 5000, 250 m square at 5 cm
constexpr int kMaxDoors = 500;            // doors of one prediction (a doors file, a request)
constexpr double kMaxDoorCells = 5e8;     // doors x map cells of one prediction (each door's room is a mask of the
                                          // map's size): 20 doors on the largest map, 500 on a million cells
constexpr double kMaxVoxels = 2e8;        // voxels of an extruded OctoMap (known cells x voxels per column): 100 s
constexpr double kMaxOctreeNodes = 3e7;   // nodes of an OctoMap being built, after pruning: 1.4 GB
constexpr int kMaxSpaces = 10000;         // spaces of an environment XML

// Throws InputError(source, "<what> is N, more than the limit of L<hint>") when value > limit; `hint` (e.g.
// ": raise the resolution") says how to stay under it.
void checkLimit(const std::string& source, const std::string& what, double value, double limit,
                const std::string& hint = "");

}  // namespace hidden_rooms::common
