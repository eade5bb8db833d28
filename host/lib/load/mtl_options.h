// The MTL texture statements envtrace reads (map_Kd, map_Ks, map_Pr, map_Ns) as tinyobjloader can
// read them. The MTL format lets
// -s, -o and -t take one to three numbers ("-s u [v [w]]"); tinyobjloader always reads three, so
// "map_Kd -s 2 2 wood.png" lost the file name to the third number and the texture vanished without
// a word. The MTL text is rewritten before tinyobjloader sees it: every such option written out
// with its defaults (scale 1, offset and turbulence 0), non-finite numbers and statements with no
// file name after their options refused, naming the file and line.
#pragma once
#include <string>

namespace et {

// `text`: an MTL file's contents; `where`: its name for errors. Lines other than texture
// statements, and texture statements with options this does not know, are returned unchanged.
std::string normalise_mtl_texture_options(const std::string& text, const std::string& where);

} // namespace et
