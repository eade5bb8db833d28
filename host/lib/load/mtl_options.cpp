#include "load/mtl_options.h"

#include "util/error.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

namespace et {
namespace {

// The texture statements envtrace reads (obj_loader.cpp); the others (map_Ka, bump, map_d, ...)
// are ignored, and pass unchanged whatever they hold.
bool is_texture_statement(const std::string& key) {
    return key == "map_Kd" || key == "map_Ks" || key == "map_Pr" || key == "map_Ns";
}

// The whole token as a number, or false.
bool parse_number(const std::string& token, double* out) {
    if (token.empty())
        return false;
    char* end = nullptr;
    *out = std::strtod(token.c_str(), &end);
    return end == token.c_str() + token.size();
}

// Splits off the next whitespace-delimited token of `line` from `pos`.
std::string next_token(const std::string& line, size_t* pos) {
    size_t b = line.find_first_not_of(" \t", *pos);
    if (b == std::string::npos) {
        *pos = line.size();
        return "";
    }
    size_t e = line.find_first_of(" \t", b);
    e = e == std::string::npos ? line.size() : e;
    *pos = e;
    return line.substr(b, e - b);
}

// One texture statement, its options written out in full; `where`: file and line for errors.
std::string normalise_statement(const std::string& line, const std::string& where) {
    size_t pos = 0;
    const std::string key = next_token(line, &pos);
    std::string out = key;
    for (;;) {
        const size_t before = pos;
        const std::string tok = next_token(line, &pos);
        if (tok.empty())
            throw Error(where + ": " + key + " names no file" +
                        (out == key ? "" : " after its options"));
        if (tok == "-s" || tok == "-o" || tok == "-t") {
            const double fallback = tok == "-s" ? 1.0 : 0.0;
            double v[3] = {fallback, fallback, fallback};
            int n = 0;
            for (; n < 3; ++n) {
                size_t p = pos;
                double x;
                if (!parse_number(next_token(line, &p), &x))
                    break;
                if (!std::isfinite(x))
                    throw Error(where + ": " + key + " " + tok + ": the numbers must be finite");
                v[n] = x;
                pos = p;
            }
            if (n == 0)
                throw Error(where + ": " + key + " " + tok + " takes one to three numbers");
            std::ostringstream s;
            s.precision(9);
            s << ' ' << tok << ' ' << v[0] << ' ' << v[1] << ' ' << v[2];
            out += s.str();
            continue;
        }
        // Options of a fixed number of arguments, passed on as they are.
        int args = -1;
        if (tok == "-blendu" || tok == "-blendv" || tok == "-bm" || tok == "-boost" ||
            tok == "-cc" || tok == "-clamp" || tok == "-imfchan" || tok == "-texres" ||
            tok == "-type" || tok == "-colorspace")
            args = 1;
        else if (tok == "-mm")
            args = 2;
        if (args < 0) // the file name (possibly with spaces), or an option unknown here
            return out + line.substr(before);
        out += ' ' + tok;
        for (int k = 0; k < args; ++k) {
            const std::string a = next_token(line, &pos);
            if (a.empty())
                throw Error(where + ": " + key + " " + tok + " is missing its value");
            out += ' ' + a;
        }
    }
}

} // namespace

std::string normalise_mtl_texture_options(const std::string& text, const std::string& where) {
    std::string out;
    out.reserve(text.size() + 64);
    size_t start = 0;
    for (int number = 1; start < text.size(); ++number) {
        size_t end = text.find('\n', start);
        end = end == std::string::npos ? text.size() : end;
        std::string line = text.substr(start, end - start);
        const bool cr = !line.empty() && line.back() == '\r';
        if (cr)
            line.pop_back();
        const size_t b = line.find_first_not_of(" \t");
        size_t pos = b == std::string::npos ? line.size() : b;
        const std::string key = next_token(line, &pos);
        if (is_texture_statement(key))
            line = line.substr(0, b) +
                   normalise_statement(line.substr(b), where + ": line " + std::to_string(number));
        out += line;
        if (cr)
            out += '\r';
        if (end < text.size())
            out += '\n';
        start = end + 1;
    }
    return out;
}

} // namespace et
