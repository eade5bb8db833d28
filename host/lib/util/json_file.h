// Reading JSON files with errors that give file, line and column, and reading their values with
// errors that give the key path (`render.spp`) and a short excerpt of the offending value.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace et {

class OutputBatch;

// Deepest nesting of arrays and objects accepted in an input file.
constexpr int kMaxJsonDepth = 64;

// Reads a regular file of at most kMaxJsonBytes (util/file_check.h) and parses it. Throws
// et::Error "PATH:LINE:COL: problem" for malformed JSON, nesting deeper than kMaxJsonDepth and
// numbers outside the range of a double (1e999); `what` names the kind of file in messages.
nlohmann::json read_json_file(const std::string& path, const char* what = "JSON file");

// The same for JSON text already read (a glTF's JSON chunk); `path` names it in messages.
nlohmann::json parse_json_text(const std::string& path, const std::string& text);

// Writes `j` (indented by `indent`) all-or-nothing (util/output_batch.h): to a temporary beside
// `path`, renamed into place; on failure throws et::Error naming `path`.
void write_json_file(const std::string& path, const nlohmann::json& j, int indent = 2);
// The same as one file of a batch, renamed into place with the others by batch.commit().
void write_json_file(OutputBatch& batch, const std::string& path, const nlohmann::json& j,
                     int indent = 2);

// At most `max` bytes of `text` (cut at a UTF-8 character boundary), with "..." when cut.
std::string excerpt(const std::string& text, size_t max = 60);

// A short description of a JSON value for messages: numbers, booleans and null as written,
// strings quoted and cut to ~60 characters, arrays and objects by type and size only.
std::string json_excerpt(const nlohmann::json& value);

// The entry of `known` closest to `key` by edit distance (case-insensitive; a swap of two
// neighbours counts once), or "" when none is close enough to be a likely misspelling.
std::string closest_key(const std::string& key, const std::vector<std::string>& known);

// Typed access to the members of a parsed file, with errors "FILE: key.path: problem (got X)".
// Numbers must be finite and in range; integers must be integral (64, 64.0 and 6.4e1 are the
// same number; 6.5 is an error); nothing is coerced across types.
class JsonReader {
  public:
    explicit JsonReader(std::string file, std::string path = "")
        : file_(std::move(file)), path_(std::move(path)) {}

    JsonReader at(const std::string& key) const; // the member `key`: path "path.key"
    JsonReader at(size_t index) const;           // the element `index`: path "path[index]"
    const std::string& file() const { return file_; }
    const std::string& path() const { return path_; }
    std::string where() const; // "FILE: path" ("FILE" at the top level)
    [[noreturn]] void fail(const std::string& problem) const;

    // The value at this reader's path, checked.
    void expect_object(const nlohmann::json& v) const;
    void expect_array(const nlohmann::json& v) const;
    double number(const nlohmann::json& v, double lo, double hi) const;
    int64_t integer(const nlohmann::json& v, int64_t lo, int64_t hi) const;
    std::string string(const nlohmann::json& v) const;
    bool boolean(const nlohmann::json& v) const;

    // Member `key` of object `j`, checked, or `fallback` when absent.
    double number(const nlohmann::json& j, const char* key, double fallback, double lo,
                  double hi) const;
    int64_t integer(const nlohmann::json& j, const char* key, int64_t fallback, int64_t lo,
                    int64_t hi) const;
    std::string string(const nlohmann::json& j, const char* key, const std::string& fallback) const;
    bool boolean(const nlohmann::json& j, const char* key, bool fallback) const;
    // The object member `key` (checked to be an object), or nullptr when absent.
    const nlohmann::json* object(const nlohmann::json& j, const char* key) const;

    // Throws "FILE: path.key: unknown key; did you mean "k"?" for the first key of `object`
    // that is not in `known` (the suggestion only when one is close, else the keys known here):
    // a misspelt key would otherwise render with the default without a word.
    void reject_unknown_keys(const nlohmann::json& object,
                             const std::vector<std::string>& known) const;

  private:
    std::string file_, path_;
};

} // namespace et
