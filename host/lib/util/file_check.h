// Opening input files safely: only regular files are read (a FIFO, a device such as /dev/zero or
// a folder is a clear error, never a hang or an endless read), and only up to a size cap. Every
// reader of user input (scene and light-set JSON, OBJ, MTL, maps) goes through here.
#pragma once
#include <cstdint>
#include <string>

namespace et {

constexpr uint64_t kMiB = uint64_t(1) << 20;
constexpr uint64_t kGiB = uint64_t(1) << 30;

// Size caps of the inputs, by kind.
constexpr uint64_t kMaxJsonBytes = 256 * kMiB; // scene files, light sets
constexpr uint64_t kMaxMeshBytes = 2 * kGiB;   // OBJ, PLY, glTF/GLB (and its buffers in all)
constexpr uint64_t kMaxMtlBytes = 64 * kMiB;   // MTL
constexpr uint64_t kMaxImageBytes = 4 * kGiB;  // maps, images to compare

// Throws et::Error "PATH: problem" unless `path` names (after symbolic links) an existing regular
// file of at most `max_bytes`; `what` names the kind of file in messages ("scene file", "map").
// Returns the file's size in bytes.
uint64_t check_regular_file(const std::string& path, uint64_t max_bytes, const char* what);

// Reads a whole regular file of at most `max_bytes` into a string. The file is opened without
// blocking and checked again on the open descriptor, so a FIFO or device swapped in after a
// check is still refused; a file that grows while read is cut off at the cap with an error.
std::string read_regular_file(const std::string& path, uint64_t max_bytes, const char* what);

// read_regular_file for text formats (scene JSON, OBJ, MTL): a UTF-8 byte order mark is dropped
// (OBJ readers take it for part of the first statement), and UTF-16 or UTF-32 text -- Notepad's
// "Unicode", PowerShell's Out-File -- is an error saying so (its NUL bytes read as no statements
// at all: "no faces", "malformed JSON").
std::string read_text_file(const std::string& path, uint64_t max_bytes, const char* what);

// A file name's extension in lower case, dot included (".exr"; "" without one): formats are
// told by extension in any case.
std::string lower_extension(const std::string& path);

// "12.3 MiB", "4 GiB": a byte count for messages.
std::string byte_text(uint64_t bytes);

} // namespace et
