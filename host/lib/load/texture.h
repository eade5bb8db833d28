// Material textures as the loaders make them: image files read through OpenImageIO (colour
// textures decoded from sRGB, data textures such as roughness as stored) and the generated
// checkerboard, held once per distinct source in a scene's TextureSet. The kernels look them
// up bilinearly with repeat addressing (kernels/texture_lookup.h).
#pragma once
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace et {

class JsonReader;

// Colour textures (albedo, specular) are 3 channels, 8- and 16-bit files decoded from sRGB;
// data textures (roughness) keep one channel (the first, or R) as stored, 8 bits / 255.
// Values are clamped to [0, 1], as material constants are; NaN becomes 0.
enum class TextureUse { colour, data };

struct Texture {
    std::string name; // the file, or "checker"
    int width = 0, height = 0, channels = 3;
    std::vector<float> texels;      // row-major from the top row, `channels` floats per texel
    glm::vec2 uv_scale{1.0f, 1.0f}; // coordinates are scaled, then offset, then wrapped
    glm::vec2 uv_offset{0.0f, 0.0f};
};

// Every texture of a scene, each source once (a file used by many materials is read once).
class TextureSet {
  public:
    // Reads `path` (already resolved) for `use`; `where` prefixes errors ("scene.json:
    // materials.wood.albedo" or "box.mtl: material 'floor': map_Kd"). Throws et::Error.
    int add_file(const std::string& path, TextureUse use, glm::vec2 uv_scale, glm::vec2 uv_offset,
                 const std::string& where);
    // Adds a texture made in memory (its texels checked against the budget); returns its index.
    int add(Texture t, const std::string& where);
    const std::vector<Texture>& textures() const { return textures_; }
    uint64_t texel_floats() const { return floats_; }

  private:
    std::vector<Texture> textures_;
    std::map<std::string, int> by_key_;
    uint64_t floats_ = 0;
};

// A checkerboard of two colours, Mitsuba 3's `checkerboard`: within each unit square of (u, v),
// colour0 where u mod 1 and v mod 1 are both below or both above 1/2, else colour1. Generated as
// 2 x 2 squares of `resolution` texels each (bilinear lookup blurs its edges over one texel).
Texture make_checker(glm::vec3 colour0, glm::vec3 colour1, int resolution);

// A material parameter that may be a texture: when `j[key]` is an object, reads it as
//   {"texture": "FILE"}  or  {"checker": {"color0": C, "color1": C, "resolution": N}}
// with optional "uv_scale" (a number or [u, v]) and "uv_offset" ([u, v]), adds it to `set` and
// returns its index; returns -1 when `j[key]` is absent or not an object (a constant, read by
// the caller). Files resolve against `dir` and the data search path. Throws et::Error naming
// the key path.
int read_texture_param(const nlohmann::json& j, const char* key, TextureUse use,
                       const std::string& dir, const JsonReader& r, TextureSet& set);

} // namespace et
