// An OpenEXR file's headers checked before OpenEXR reads them. OpenEXR 3.1 allocates what its
// headers claim before it can tell that the file does not hold it: an attribute's size field
// (fuzz finding F10), a value that parses to a different length than its size field, after
// which the rest of the header is read out of step (F11), the chunk offset tables (from the
// data window, the tiles, the compression or chunkCount), and it fills in a 64x64 data window
// when the header has none. So every header is read here first, as OpenEXR reads it.
#pragma once
#include <cstdint>
#include <string>

namespace et {

// What the reader needs of the first part (the one that is read).
struct ExrHeaderInfo {
    int64_t width = 0, height = 0; // of the data window
    uint64_t stored_bytes = 0;     // of every channel, uncompressed
    int channels = 0;
    bool tiled = false;
    int parts = 0;
};

// Walks every header of the EXR file at `path` (which starts with the EXR magic) and throws
// et::Error "PATH: corrupt EXR header: PROBLEM" (or "PATH: ... not supported") unless:
// - the version is 2 with known flags, and the file is not deep;
// - every attribute has a name and a type of at most 255 bytes, appears once per header, and
//   its size fits in the rest of the file and is exactly the length its type parses to (fixed
//   sizes, channel lists, string vectors, previews, float vectors);
// - each header has channels (at least one; types UINT, HALF or FLOAT; sampling at least 1 and
//   dividing the data window, 1 in tiled files; no name twice), compression (a known method),
//   dataWindow and displayWindow (not empty, within OpenEXR's +-2^30), lineOrder; tiled parts
//   tiles (known level and rounding modes, tiles of at most the memory budget); parts of a
//   multi-part file name, type (scanline or tiled image) and a chunkCount equal to what the
//   part's size, compression and tiling make;
// - the chunk offset tables, and the smallest chunk of each entry, fit in the file after the
//   headers.
// Reads at most the headers; returns the first part's size and layout.
ExrHeaderInfo check_exr_header(const std::string& path, uint64_t file_bytes);

} // namespace et
