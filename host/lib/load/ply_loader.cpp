// PLY meshes (Turk's polygon file format): ASCII and binary little/big endian, the vertex
// element's x, y, z (and nx, ny, nz, u/v or s/t when present) and the face element's vertex index
// lists, polygons triangulated as fans. A small reader of our own rather than a large dependency:
// every count is checked against the bytes left in the file before anything is allocated, so a
// hostile file is an error naming the file and the problem, never a crash or a huge allocation.
#include "util/error.h"
#include "util/file_check.h"
#include "util/json_file.h"
#include "load/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace et {

namespace {

enum class PlyFormat { ascii, little, big };

// A scalar type of the format: its size in bytes and whether it is a float or signed integer.
struct PlyType {
    int bytes = 0;
    bool is_float = false, is_signed = false;
};

bool ply_type(const std::string& name, PlyType& t) {
    static const struct {
        const char* name;
        PlyType type;
    } kTypes[] = {
        {"char", {1, false, true}},    {"int8", {1, false, true}},    {"uchar", {1, false, false}},
        {"uint8", {1, false, false}},  {"short", {2, false, true}},   {"int16", {2, false, true}},
        {"ushort", {2, false, false}}, {"uint16", {2, false, false}}, {"int", {4, false, true}},
        {"int32", {4, false, true}},   {"uint", {4, false, false}},   {"uint32", {4, false, false}},
        {"float", {4, true, true}},    {"float32", {4, true, true}},  {"double", {8, true, true}},
        {"float64", {8, true, true}}};
    for (const auto& k : kTypes)
        if (name == k.name) {
            t = k.type;
            return true;
        }
    return false;
}

struct PlyProperty {
    std::string name;
    PlyType type;
    bool is_list = false;
    PlyType count_type; // lists: the type of the element count before the items
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
};

// Reads values one at a time from the body, ASCII or binary, with the file's name and the place
// in every error.
class PlyBody {
  public:
    PlyBody(const std::string& path, const std::string& data, size_t pos, PlyFormat format)
        : path_(path), data_(data), pos_(pos), format_(format) {}

    double read(const PlyType& t, const char* what) {
        if (format_ == PlyFormat::ascii)
            return read_ascii(t, what);
        if (data_.size() - pos_ < static_cast<size_t>(t.bytes))
            fail(std::string("truncated: the file ends inside ") + what);
        // b: the value's bytes little-endian. Floats are then copied out (the host is
        // little-endian x86-64 / AArch64); integers are assembled by shifts.
        const int n = std::min(t.bytes, 8);
        const unsigned char* src = reinterpret_cast<const unsigned char*>(data_.data()) + pos_;
        unsigned char b[8] = {};
        for (int k = 0; k < n; ++k)
            b[k] = src[format_ == PlyFormat::big ? n - 1 - k : k];
        pos_ += n;
        if (t.is_float) {
            if (t.bytes == 4) {
                float f;
                std::memcpy(&f, b, 4);
                return f;
            }
            double d;
            std::memcpy(&d, b, 8);
            return d;
        }
        uint64_t u = 0;
        for (int k = t.bytes - 1; k >= 0; --k)
            u = (u << 8) | b[k];
        if (t.is_signed && (u >> (8 * t.bytes - 1)) & 1) // sign-extend
            return static_cast<double>(static_cast<int64_t>(u | (~uint64_t(0) << (8 * t.bytes))));
        return static_cast<double>(u);
    }

    size_t remaining() const { return data_.size() - pos_; }

    // ASCII: an element's row is one line (the PLY format's rule), so a line with a value too
    // few or too many fails here rather than shifting every row after it. Binary: nothing.
    void begin_row() {
        if (format_ != PlyFormat::ascii)
            return;
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_])))
            ++pos_;
        in_row_ = true;
    }
    void end_row(const std::string& element, uint64_t row) {
        if (format_ != PlyFormat::ascii)
            return;
        skip_blanks();
        if (pos_ < data_.size() && data_[pos_] != '\n') {
            size_t end = data_.find('\n', pos_);
            end = end == std::string::npos ? data_.size() : end;
            std::string rest(data_, pos_, std::min<size_t>(20, end - pos_));
            while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.back())))
                rest.pop_back();
            fail("element '" + element + "' row " + std::to_string(row) +
                 ": more values on the line than the header declares ('" + excerpt(rest) +
                 "' left)");
        }
        in_row_ = false;
    }

    // "PATH: PLY: line L: problem" (ASCII) or "PATH: PLY: byte B: problem" (binary): the place
    // the reader had reached.
    [[noreturn]] void fail(const std::string& problem) const {
        std::string place;
        if (format_ == PlyFormat::ascii)
            place =
                "line " + std::to_string(1 + std::count(data_.begin(), data_.begin() + pos_, '\n'));
        else
            place = "byte " + std::to_string(pos_);
        throw Error(path_ + ": PLY: " + place + ": " + problem);
    }

  private:
    void skip_blanks() { // within a line
        while (pos_ < data_.size() && data_[pos_] != '\n' &&
               std::isspace(static_cast<unsigned char>(data_[pos_])))
            ++pos_;
    }

    double read_ascii(const PlyType& t, const char* what) {
        if (in_row_)
            skip_blanks();
        else
            while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_])))
                ++pos_;
        if (pos_ >= data_.size())
            fail(std::string("truncated: the file ends before ") + what);
        if (data_[pos_] == '\n')
            fail(std::string("the line ends before ") + what +
                 " (fewer values than the header declares)");
        // std::string's buffer is NUL-terminated, so strtod stops at the end.
        const char* begin = data_.c_str() + pos_;
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (end == begin ||
            (end < data_.c_str() + data_.size() && !std::isspace(static_cast<unsigned char>(*end))))
            fail(std::string("not a number in ") + what + ": '" +
                 excerpt(std::string(begin, std::min<size_t>(20, data_.size() - pos_))) + "'");
        pos_ = end - data_.c_str();
        if (!t.is_float && (v != std::floor(v) || std::fabs(v) > 4.3e9))
            fail(std::string("not an integer in ") + what);
        return v;
    }

    const std::string& path_;
    const std::string& data_;
    size_t pos_;
    PlyFormat format_;
    bool in_row_ = false;
};

// More than this many vertices or faces is refused before allocating (about 10 GiB of soup).
constexpr uint64_t kMaxPlyElements = uint64_t(1) << 28;
// A polygon with more corners than this is not a face any modeller writes.
constexpr double kMaxPolygonCorners = 1 << 16;

} // namespace

void load_ply(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out) {
    const std::string data = read_regular_file(path, kMaxMeshBytes, "PLY file");
    auto fail = [&](const std::string& problem) { throw Error(path + ": PLY: " + problem); };

    // Header: text lines up to "end_header".
    if (data.compare(0, 4, "ply\n") != 0 && data.compare(0, 5, "ply\r\n") != 0)
        throw Error(path + ": not a PLY file (it does not start with the line 'ply')");
    size_t pos = 0, line_no = 0;
    bool have_format = false, ended = false;
    PlyFormat format = PlyFormat::ascii;
    std::vector<PlyElement> elements;
    while (!ended) {
        const size_t eol = data.find('\n', pos);
        if (eol == std::string::npos || eol - pos > 4096)
            fail("truncated or malformed header (no 'end_header' line)");
        std::string line = data.substr(pos, eol - pos);
        pos = eol + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        std::vector<std::string> w;
        for (size_t i = 0; i < line.size();) {
            while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i])))
                ++i;
            size_t j = i;
            while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j])))
                ++j;
            if (j > i)
                w.push_back(line.substr(i, j - i));
            i = j;
        }
        const std::string where = "header line " + std::to_string(line_no) + ": ";
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info" || (line_no == 1 && w[0] == "ply"))
            continue;
        if (w[0] == "format") {
            if (w.size() < 2)
                fail(where + "format needs a name");
            if (w[1] == "ascii")
                format = PlyFormat::ascii;
            else if (w[1] == "binary_little_endian")
                format = PlyFormat::little;
            else if (w[1] == "binary_big_endian")
                format = PlyFormat::big;
            else
                fail(where + "unknown format '" + excerpt(w[1], 40) +
                     "' (ascii, binary_little_endian or binary_big_endian)");
            have_format = true;
        } else if (w[0] == "element") {
            if (w.size() != 3)
                fail(where + "'element' needs a name and a count");
            PlyElement e;
            e.name = w[1];
            char* end = nullptr;
            const unsigned long long n = std::strtoull(w[2].c_str(), &end, 10);
            if (*end != '\0' || w[2][0] == '-')
                fail(where + "element count '" + excerpt(w[2], 40) + "' is not a count");
            if (n > kMaxPlyElements)
                fail(where + "element '" + excerpt(e.name, 40) + "' count " + w[2] +
                     " is beyond the limit of " + std::to_string(kMaxPlyElements));
            e.count = n;
            // One of each: the property lookups below are per element name.
            for (const auto& prev : elements)
                if ((e.name == "vertex" || e.name == "face") && prev.name == e.name)
                    fail(where + "a second '" + e.name + "' element");
            elements.push_back(e);
        } else if (w[0] == "property") {
            if (elements.empty())
                fail(where + "a property before any element");
            PlyProperty p;
            if (w.size() == 5 && w[1] == "list") {
                p.is_list = true;
                if (!ply_type(w[2], p.count_type) || p.count_type.is_float)
                    fail(where + "list count type '" + excerpt(w[2], 40) +
                         "' is not an integer type");
                if (!ply_type(w[3], p.type))
                    fail(where + "unknown type '" + excerpt(w[3], 40) + "'");
                p.name = w[4];
            } else if (w.size() == 3) {
                if (!ply_type(w[1], p.type))
                    fail(where + "unknown type '" + excerpt(w[1], 40) + "'");
                p.name = w[2];
            } else {
                fail(where + "malformed property line '" + excerpt(line, 60) + "'");
            }
            elements.back().props.push_back(p);
        } else if (w[0] == "end_header") {
            ended = true;
        } else {
            fail(where + "unknown keyword '" + excerpt(w[0], 40) + "'");
        }
    }
    if (!have_format)
        fail("the header has no 'format' line");

    // The counts against the bytes left: each row needs at least its fixed-size part in binary,
    // and at least two characters (a digit and a separator) per value in ASCII.
    const size_t body_bytes = data.size() - pos;
    for (const auto& e : elements) {
        uint64_t row = 0;
        for (const auto& p : e.props)
            row += format == PlyFormat::ascii ? 2 : (p.is_list ? p.count_type.bytes : p.type.bytes);
        if (row > 0 && e.count > body_bytes / row)
            fail("element '" + excerpt(e.name, 40) + "' claims " + std::to_string(e.count) +
                 " rows, more than the " + byte_text(body_bytes) +
                 " after the header can hold (truncated or corrupt)");
    }

    // The vertex element's properties we read, by index into its property list.
    std::vector<glm::vec3> pos_v, nrm_v;
    std::vector<glm::vec2> uv_v;
    bool has_normals = false, has_uvs = false;
    int face_list = -1;
    for (const auto& e : elements) {
        if (e.name == "vertex") {
            auto find = [&](std::initializer_list<const char*> names) {
                for (size_t i = 0; i < e.props.size(); ++i)
                    for (const char* n : names)
                        if (e.props[i].name == n && !e.props[i].is_list)
                            return static_cast<int>(i);
                return -1;
            };
            if (find({"x"}) < 0 || find({"y"}) < 0 || find({"z"}) < 0)
                fail("the vertex element has no x, y, z properties");
            has_normals = find({"nx"}) >= 0 && find({"ny"}) >= 0 && find({"nz"}) >= 0;
            has_uvs = (find({"u", "s", "texture_u", "texture_s"}) >= 0 &&
                       find({"v", "t", "texture_v", "texture_t"}) >= 0);
        }
        if (e.name == "face") {
            for (size_t i = 0; i < e.props.size(); ++i)
                if (e.props[i].is_list &&
                    (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
                    face_list = static_cast<int>(i);
            if (face_list < 0)
                fail("the face element has no 'vertex_indices' list");
        }
    }

    int mat = override_material;
    if (mat < 0) {
        mat = static_cast<int>(materials.size());
        Material grey;
        grey.name = path + ":default";
        materials.push_back(grey);
    }
    const glm::mat3 normal_m = glm::transpose(glm::inverse(glm::mat3(transform)));

    PlyBody body(path, data, pos, format);
    // Faces of fewer than three corners, and the triangles the other faces fan into: read and
    // skipped (degenerate, non-finite, out of range).
    size_t short_faces = 0, triangles_read = 0, dropped = 0;
    bool have_vertices = false;
    for (const auto& e : elements) {
        const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
        if (is_vertex) {
            pos_v.assign(e.count, glm::vec3(0.0f));
            if (has_normals)
                nrm_v.assign(e.count, glm::vec3(0.0f));
            if (has_uvs)
                uv_v.assign(e.count, glm::vec2(0.0f));
            have_vertices = true;
        }
        if (is_face && !have_vertices)
            fail("the face element comes before the vertex element");
        for (uint64_t row = 0; row < e.count; ++row) {
            body.begin_row();
            for (size_t pi = 0; pi < e.props.size(); ++pi) {
                const PlyProperty& p = e.props[pi];
                if (p.is_list) {
                    const double n = body.read(p.count_type, "a list count");
                    if (n < 0 || n > kMaxPolygonCorners)
                        body.fail("element '" + excerpt(e.name, 40) + "' row " +
                                  std::to_string(row) + ": list count " +
                                  std::to_string(static_cast<long long>(n)) + " is out of range");
                    const size_t count = static_cast<size_t>(n);
                    if (format != PlyFormat::ascii &&
                        count * static_cast<size_t>(p.type.bytes) > body.remaining())
                        body.fail("truncated: element '" + excerpt(e.name, 40) + "' row " +
                                  std::to_string(row) + " runs past the end of the file");
                    if (!(is_face && static_cast<int>(pi) == face_list)) {
                        for (size_t k = 0; k < count; ++k)
                            body.read(p.type, "a list item");
                        continue;
                    }
                    std::vector<uint32_t> idx(count);
                    for (size_t k = 0; k < count; ++k) {
                        const double v = body.read(p.type, "a face's vertex index");
                        if (!(v >= 0 && v < static_cast<double>(pos_v.size())))
                            body.fail("face " + std::to_string(row) + ": vertex index " +
                                      std::to_string(static_cast<long long>(v)) +
                                      " is out of range (" + std::to_string(pos_v.size()) +
                                      " vertices)");
                        idx[k] = static_cast<uint32_t>(v);
                    }
                    if (count < 3) {
                        ++short_faces;
                        continue;
                    }
                    triangles_read += count - 2;
                    for (size_t k = 1; k + 1 < count; ++k) { // a fan about corner 0
                        const uint32_t c[3] = {idx[0], idx[k], idx[k + 1]};
                        glm::vec3 pp[3], nn[3];
                        glm::vec2 tt[3];
                        for (int q = 0; q < 3; ++q) {
                            pp[q] = glm::vec3(transform * glm::vec4(pos_v[c[q]], 1.0f));
                            if (has_normals)
                                nn[q] = normal_m * nrm_v[c[q]];
                            if (has_uvs)
                                tt[q] = uv_v[c[q]];
                        }
                        if (!add_triangle(out, pp, has_normals ? nn : nullptr, mat,
                                          has_uvs ? tt : nullptr))
                            ++dropped;
                    }
                    continue;
                }
                const double v = body.read(p.type, "a vertex or element value");
                if (!is_vertex)
                    continue;
                const float f = static_cast<float>(v);
                const std::string& n = p.name;
                if (n == "x" || n == "y" || n == "z") {
                    if (!std::isfinite(f)) {
                        char text[32];
                        std::snprintf(text, sizeof text, "%.9g", v);
                        body.fail("vertex " + std::to_string(row) + ": coordinate " + n + " (" +
                                  text + ") is not a finite float");
                    }
                    pos_v[row][n[0] - 'x'] = f;
                } else if (has_normals && (n == "nx" || n == "ny" || n == "nz")) {
                    nrm_v[row][n[1] - 'x'] = f;
                } else if (has_uvs &&
                           (n == "u" || n == "s" || n == "texture_u" || n == "texture_s")) {
                    uv_v[row].x = f;
                } else if (has_uvs &&
                           (n == "v" || n == "t" || n == "texture_v" || n == "texture_t")) {
                    uv_v[row].y = f;
                }
            }
            body.end_row(excerpt(e.name, 40), row);
        }
    }
    if (!have_vertices)
        fail("no vertex element");
    if (face_list < 0)
        fail("no face element (a point cloud has nothing to render)");
    if (short_faces)
        warn(path + ": " + std::to_string(short_faces) +
             " faces of fewer than three corners skipped");
    if (dropped)
        warn(path + ": " + std::to_string(dropped) + " of " + std::to_string(triangles_read) +
             " triangles skipped (degenerate, non-finite or out of range)");
}

} // namespace et
