#pragma once

// A file built into a library, so that nothing has to be found at run time: HIDDEN_ROOMS_EMBED_FILE(name, PATH)
// at namespace scope of one source file (PATH a string literal, usually a compile definition set by CMake, which
// also rebuilds that source when the file changes) defines the bytes [name, name_end) of the file's contents.
#define HIDDEN_ROOMS_EMBED_FILE(name, path)   \
  asm(".pushsection .rodata\n"                \
      ".balign 16\n" #name ":\n"              \
      ".incbin \"" path "\"\n" #name "_end:\n" \
      ".byte 0\n"                             \
      ".popsection\n");                       \
  extern "C" const char name[];               \
  extern "C" const char name##_end[]
