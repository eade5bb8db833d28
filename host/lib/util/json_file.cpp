#include "util/json_file.h"

#include "util/error.h"
#include "util/file_check.h"
#include "util/output_batch.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>
#include <unistd.h>

namespace et {
namespace {

using json = nlohmann::json;

std::string position(const std::string& path, const std::string& text, size_t pos) {
    pos = std::min(pos, text.size());
    size_t line = 1, col = 1;
    for (size_t i = 0; i < pos; ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return path + ":" + std::to_string(line) + ":" + std::to_string(col);
}

// What nlohmann's parser does not bound: nesting depth (its error messages and other recursive
// walks use the stack) and numbers that overflow a double (it throws out_of_range.406 with no
// position). One pass over the text, skipping strings, finds both with their position.
// Also refused: a key twice in one object, which nlohmann resolves silently (the last wins), so
// that a scene's second "spp" would hide its first without a word.
void prescan(const std::string& path, const std::string& text) {
    int depth = 0;
    // Per open container: whether it is an object, and the keys seen in it (their text as
    // written, with the position of the first).
    std::vector<std::pair<bool, std::map<std::string, size_t>>> open;
    const size_t n = text.size();
    for (size_t i = 0; i < n; ++i) {
        const char c = text[i];
        if (c == '"') {
            const size_t start = i;
            for (++i; i < n && text[i] != '"'; ++i)
                if (text[i] == '\\')
                    ++i;
            if (open.empty() || !open.back().first)
                continue;
            size_t next = i + 1;
            while (next < n && std::isspace(static_cast<unsigned char>(text[next])))
                ++next;
            if (next >= n || text[next] != ':')
                continue;
            const std::string key = text.substr(start + 1, std::min(i, n) - start - 1);
            auto [it, inserted] = open.back().second.emplace(key, start);
            if (!inserted)
                throw Error(position(path, text, start) + ": duplicate key \"" + excerpt(key, 40) +
                            "\" in one object (first at " + position(path, text, it->second) +
                            "): which one is meant?");
        } else if (c == '[' || c == '{') {
            if (++depth > kMaxJsonDepth)
                throw Error(position(path, text, i) + ": malformed JSON: nested deeper than " +
                            std::to_string(kMaxJsonDepth) + " levels");
            open.push_back({c == '{', {}});
        } else if (c == ']' || c == '}') {
            --depth;
            if (!open.empty())
                open.pop_back();
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            size_t end = i;
            while (end < n &&
                   (std::isdigit(static_cast<unsigned char>(text[end])) || text[end] == '-' ||
                    text[end] == '+' || text[end] == '.' || text[end] == 'e' || text[end] == 'E'))
                ++end;
            const std::string token = text.substr(i, end - i);
            errno = 0;
            const double v = std::strtod(token.c_str(), nullptr);
            if (std::isinf(v))
                throw Error(position(path, text, i) + ": number " + excerpt(token, 40) +
                            " is out of range (a double holds at most about 1.8e308)");
            i = end - 1;
        }
    }
}

// The shortest text that reads back as v (as the float v is, if it is one: a float limit such as
// 0.05f shows as 0.05): a limit and a value that differ show different digits.
std::string number_text(double v) {
    char buf[32];
    const float f = static_cast<float>(v);
    const auto r = static_cast<double>(f) == v ? std::to_chars(buf, buf + sizeof buf, f)
                                               : std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

} // namespace

// The longest prefix of `text` of at most `max` bytes that does not split a UTF-8 sequence.
static std::string utf8_prefix(const std::string& text, size_t max) {
    if (text.size() <= max)
        return text;
    size_t cut = max;
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80)
        --cut;
    return text.substr(0, cut);
}

std::string excerpt(const std::string& text, size_t max) {
    return text.size() <= max ? text : utf8_prefix(text, max) + "...";
}

std::string json_excerpt(const json& v) {
    switch (v.type()) {
    case json::value_t::object:
        return "an object of " + std::to_string(v.size()) + (v.size() == 1 ? " key" : " keys");
    case json::value_t::array:
        return "an array of " + std::to_string(v.size()) +
               (v.size() == 1 ? " element" : " elements");
    case json::value_t::string: {
        const std::string& s = v.get_ref<const std::string&>();
        return json(utf8_prefix(s, 60)).dump(-1, ' ', false, json::error_handler_t::replace) +
               (s.size() > 60 ? "..." : "");
    }
    case json::value_t::number_float:
        return number_text(v.get<double>());
    default:
        return v.dump(-1, ' ', false, json::error_handler_t::replace);
    }
}

json read_json_file(const std::string& path, const char* what) {
    return parse_json_text(path, read_text_file(path, kMaxJsonBytes, what));
}

json parse_json_text(const std::string& path, const std::string& text) {
    prescan(path, text);
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        // e.byte is 1-based and points just past the offending character.
        const size_t pos = e.byte > 0 ? e.byte - 1 : 0;
        std::string msg = e.what();
        auto colon = msg.rfind(": ");
        if (colon != std::string::npos)
            msg = msg.substr(colon + 2);
        // The message quotes the last token read, which can be a whole long string.
        msg = excerpt(msg, 120);
        throw Error(position(path, text, pos) + ": malformed JSON: " + msg);
    } catch (const json::exception& e) {
        // Anything else the prescan did not foresee: still one line, with the file.
        throw Error(path + ": malformed JSON: " + excerpt(e.what(), 120));
    }
}

void write_json_file(OutputBatch& batch, const std::string& path, const json& j, int indent) {
    batch.write(path, [&](const std::string& file) {
        errno = 0;
        std::ofstream f(file);
        if (f)
            f << j.dump(indent, ' ', false, json::error_handler_t::replace) << "\n";
        f.close();
        if (!f) {
            const int err = errno;
            throw Error(path + ": cannot write" +
                        (err ? std::string(": ") + std::strerror(err) : std::string()));
        }
    });
}

void write_json_file(const std::string& path, const json& j, int indent) {
    OutputBatch batch({path});
    write_json_file(batch, path, j, indent);
    batch.commit();
}

std::string closest_key(const std::string& key, const std::vector<std::string>& known) {
    // Optimal string alignment distance over lower-cased bytes.
    const auto lower = [](std::string t) {
        for (char& c : t)
            c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return t;
    };
    const std::string a = lower(key);
    std::string best;
    size_t best_distance = std::string::npos;
    for (const std::string& candidate : known) {
        const std::string b = lower(candidate);
        std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
        for (size_t i = 0; i <= a.size(); ++i)
            d[i][0] = i;
        for (size_t j = 0; j <= b.size(); ++j)
            d[0][j] = j;
        for (size_t i = 1; i <= a.size(); ++i)
            for (size_t j = 1; j <= b.size(); ++j) {
                const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
                d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
                if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                    d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        if (d[a.size()][b.size()] < best_distance) {
            best_distance = d[a.size()][b.size()];
            best = candidate;
        }
    }
    // About one edit in three characters, at least one: "roughnes" and "colr" are found, "fov"
    // is not taken for "eye".
    const size_t allowed = std::max<size_t>(1, (std::min(a.size(), best.size()) + 1) / 3);
    // Never a key with every character replaced ("x" for "k").
    return best_distance <= allowed && best_distance < a.size() ? best : std::string();
}

// JsonReader

JsonReader JsonReader::at(const std::string& key) const {
    const std::string k = excerpt(key, 40);
    return JsonReader(file_, path_.empty() ? k : path_ + "." + k);
}

JsonReader JsonReader::at(size_t index) const {
    return JsonReader(file_, path_ + "[" + std::to_string(index) + "]");
}

std::string JsonReader::where() const {
    return path_.empty() ? file_ : file_ + ": " + path_;
}

void JsonReader::fail(const std::string& problem) const {
    throw Error(where() + ": " + problem);
}

void JsonReader::expect_object(const json& v) const {
    if (!v.is_object())
        fail("expected an object, got " + json_excerpt(v));
}

void JsonReader::expect_array(const json& v) const {
    if (!v.is_array())
        fail("expected an array, got " + json_excerpt(v));
}

// Limits are often floats (0.05f, 1e12f, a float 4 pi) and values are written by programs that
// round in double: a value that equals a limit once both are rounded to float is inside (it is a
// float where it is used), and comes back clamped to the limits.
double JsonReader::number(const json& v, double lo, double hi) const {
    const double x = v.is_number() ? v.get<double>() : NAN;
    const auto below = [](double a, double b) { return a < b && float(a) < float(b); };
    if (!v.is_number() || !std::isfinite(x) || below(x, lo) || below(hi, x))
        fail("expected a number in [" + number_text(lo) + ", " + number_text(hi) + "], got " +
             json_excerpt(v));
    return std::clamp(x, lo, hi);
}

int64_t JsonReader::integer(const json& v, int64_t lo, int64_t hi) const {
    bool ok = false;
    int64_t x = 0;
    if (v.is_number_unsigned()) {
        const uint64_t u = v.get<uint64_t>();
        ok = u <= static_cast<uint64_t>(INT64_MAX);
        x = static_cast<int64_t>(u);
    } else if (v.is_number_integer()) {
        x = v.get<int64_t>();
        ok = true;
    } else if (v.is_number_float()) {
        // 64.0 and 6.4e1 are integers written as floats: harmless, accepted.
        const double d = v.get<double>();
        ok = std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15;
        x = ok ? static_cast<int64_t>(d) : 0;
    }
    if (!ok || x < lo || x > hi)
        fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
             "], got " + json_excerpt(v));
    return x;
}

std::string JsonReader::string(const json& v) const {
    if (!v.is_string())
        fail("expected a string, got " + json_excerpt(v));
    std::string s = v.get<std::string>();
    // A "\u0000" would cut a file name short where the operating system reads it (another file
    // opened, or an output written under a truncated name): no name or path of a scene holds one.
    if (s.find('\0') != std::string::npos)
        fail("contains a NUL character (\\u0000) at position " + std::to_string(s.find('\0')) +
             ": " + json_excerpt(v));
    return s;
}

bool JsonReader::boolean(const json& v) const {
    if (!v.is_boolean())
        fail("expected true or false, got " + json_excerpt(v));
    return v.get<bool>();
}

double JsonReader::number(const json& j, const char* key, double fallback, double lo,
                          double hi) const {
    auto it = j.find(key);
    return it == j.end() ? fallback : at(key).number(*it, lo, hi);
}

int64_t JsonReader::integer(const json& j, const char* key, int64_t fallback, int64_t lo,
                            int64_t hi) const {
    auto it = j.find(key);
    return it == j.end() ? fallback : at(key).integer(*it, lo, hi);
}

std::string JsonReader::string(const json& j, const char* key, const std::string& fallback) const {
    auto it = j.find(key);
    return it == j.end() ? fallback : at(key).string(*it);
}

bool JsonReader::boolean(const json& j, const char* key, bool fallback) const {
    auto it = j.find(key);
    return it == j.end() ? fallback : at(key).boolean(*it);
}

const json* JsonReader::object(const json& j, const char* key) const {
    auto it = j.find(key);
    if (it == j.end())
        return nullptr;
    at(key).expect_object(*it);
    return &*it;
}

void JsonReader::reject_unknown_keys(const json& object,
                                     const std::vector<std::string>& known) const {
    if (!object.is_object())
        return;
    for (auto it = object.begin(); it != object.end(); ++it) {
        if (std::find(known.begin(), known.end(), it.key()) != known.end())
            continue;
        const std::string near = closest_key(it.key(), known);
        if (!near.empty())
            at(it.key()).fail("unknown key; did you mean \"" + near + "\"?");
        std::string list;
        for (const std::string& k : known)
            list += (list.empty() ? "" : ", ") + k;
        at(it.key()).fail("unknown key (known here: " + list + ")");
    }
}

} // namespace et
