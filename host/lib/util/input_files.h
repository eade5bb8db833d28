// The files this process has read as input (scene, map, meshes, MTL, light sets, images): every
// reader goes through util/file_check, which notes each file here. Writers consult it so that no
// output ever replaces an input of the same run (`-o map.exr`, a PNG twin named like the map).
#pragma once
#include <string>

namespace et {

// Records that `path` (a regular file with this device and inode) was read as `what`.
void note_input_file(const std::string& path, const char* what, unsigned long long device,
                     unsigned long long inode);

// If `path` is (after links) one of the files read as input, "the map 'PATH'" (its kind and the
// name it was read by); else the empty string. A path that does not exist is no input.
std::string input_file_named(const std::string& path);

} // namespace et
