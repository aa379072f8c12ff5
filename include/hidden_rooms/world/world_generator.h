#pragma once

#include <cstdint>
#include <string>

#include "hidden_rooms/world/environment.h"

namespace hidden_rooms::world {

// Size classes by number of closable doors, as in the thesis (docs/method.md#batch-analysis): small < 10, medium
// 10..15, large >= 16.
enum class SizeClass { kSmall, kMedium, kLarge };

SizeClass sizeClassOf(int closable_doors);
SizeClass sizeClassOf(const Environment& environment);
const char* toString(SizeClass size_class);
// Parses "small" | "medium" | "large"; throws InputError otherwise.
SizeClass parseSizeClass(const std::string& text);

// Procedurally generates an office/school-like floor: corridors with rooms of varied sizes along them, one
// door per room and some rooms with two doors, in the thesis's XML model. The result is in `size_class`,
// every space is reachable with all doors open, and the same seed and class always give the same world.
Environment generateWorld(std::uint32_t seed, SizeClass size_class);

}  // namespace hidden_rooms::world
