#pragma once
/// @file json_reader.hpp
/// Checked reading of JSON scene files: every value read is checked for type and range, every
/// object for unknown keys (with a "did you mean" hint), and every message names the file, the
/// JSON pointer (RFC 6901), what was found and what was expected. Errors are collected so that
/// `simreel validate` can print all of them; SceneError carries the list.

#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "simreel/sim/ranges.hpp"

namespace simreel::app {

using nlohmann::json;

/// Bad input (scene file, --set override, asset): exit code 2. `what()` is all messages, one
/// per line; `messages()` lists them.
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(std::vector<std::string> messages);
  explicit SceneError(const std::string& message) : SceneError(std::vector<std::string>{message}) {}
  [[nodiscard]] const std::vector<std::string>& messages() const { return messages_; }

 private:
  std::vector<std::string> messages_;
};

/// Levenshtein distance, for "did you mean" hints.
std::size_t edit_distance(const std::string& a, const std::string& b);

/// Escapes one reference token for a JSON pointer (~ -> ~0, / -> ~1).
std::string pointer_token(const std::string& key);

/// Short description of a JSON value for messages: `"fast" (string)`, `-3 (number)`, `an object`.
std::string describe(const json& value);

/// Parses JSON text. @throws SceneError "FILE:LINE:COL: invalid JSON: ..." on a syntax error.
json parse_json_text(const std::string& text, const std::string& file);
/// Reads and parses a file. @throws SceneError naming the file if it cannot be read or parsed.
json parse_json_file(const std::filesystem::path& path, const std::string& what = "scene");

/// The largest JSON file (scene, golden) read: 64 MiB. Larger files are refused before reading.
inline constexpr std::uintmax_t kMaxJsonBytes = 64ull << 20;

/// The contents of `path`, which must be a regular file (not a FIFO, device or directory) of at
/// most `limit` bytes. @throws SceneError "FILE: cannot read WHAT: why".
std::string read_regular_file(const std::filesystem::path& path, const std::string& what, std::uintmax_t limit);

/// The largest magnitude of a 3-vector's component in a scene (ObjectReader::vec3): below the
/// largest float, 3.4e38.
inline constexpr double kMaxVectorComponent = 3e38;

/// The most frames a run may have: the scene's "frames", --frames N or A:B, and a golden's
/// "frames" end (one cap for every way of giving a frame count).
inline constexpr long long kMaxFrames = 1'000'000;

/// The whole of `text` as a decimal integer in [min, max] (std::from_chars: no overflow, no
/// sign other than '-', no spaces or trailing characters); nullopt otherwise.
std::optional<long long> parse_integer(std::string_view text, long long min, long long max);

/// "A<separator>B" with A and B each as parse_integer reads them; nullopt otherwise.
std::optional<std::pair<long long, long long>> parse_pair(std::string_view text, char separator, long long min,
                                                          long long max);

/// Applies `--set POINTER=VALUE`: VALUE is read as JSON, and as a string if it is not JSON.
/// The pointer must name an existing value or a new key of an existing object (the schema check
/// then rejects an unknown key). @throws SceneError naming the override and the file.
void apply_override(json& doc, const std::string& assignment, const std::string& file);

/// What the readers read, recorded for the JSON Schema (`simreel schema`) and for hints: while a
/// KeyLog::Scope is alive on a thread, every ObjectReader on that thread records each key it
/// reads with a JSON Schema of the value it accepts (type, range, default), under the object's
/// pointer with array indices written as "*" ("/emitters/*/split"). The loader's own reads are
/// the key table: nothing is listed twice.
class KeyLog {
 public:
  /// Installs `log` for this thread until destroyed (the previous one is restored).
  class Scope {
   public:
    explicit Scope(KeyLog& log);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    KeyLog* previous_;
  };
  /// The log installed on this thread, or nullptr (the normal case: nothing is recorded).
  static KeyLog* current();

  /// Records `schema` for `key` of the object at `pointer`. A bare `{}` (a key read raw) never
  /// replaces a typed schema; different typed schemas for one key are kept side by side (anyOf).
  void add(const std::string& pointer, const std::string& key, const json& schema);
  /// Objects (normalised pointers) -> keys in first-read order -> accepted schemas.
  [[nodiscard]] const std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::vector<json>>>>>&
  objects() const {
    return objects_;
  }
  /// The keys read in the object at `pointer` (normalised), in first-read order.
  [[nodiscard]] std::vector<std::string> keys(const std::string& pointer) const;

  /// "/emitters/3/split" -> "/emitters/*/split".
  static std::string normalise(const std::string& pointer);

 private:
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::vector<json>>>>> objects_;
};

/// One JSON object being read. Keys read through it are "known"; finish() reports the others.
class ObjectReader {
 public:
  ObjectReader(const json& object, std::string pointer, std::string file,
               std::vector<std::string>& errors);

  [[nodiscard]] bool has(const std::string& key) const;
  [[nodiscard]] std::string pointer(const std::string& key) const { return pointer_ + "/" + pointer_token(key); }
  [[nodiscard]] const std::string& pointer() const { return pointer_; }
  [[nodiscard]] const std::string& file() const { return file_; }
  std::vector<std::string>& errors() { return errors_; }

  /// Marks a key known without reading it (a key handled elsewhere).
  void known(const std::string& key) {
    known_.insert(key);
    record(key, json::object());
  }
  /// The raw value of key, or nullptr if absent (marks the key known).
  const json* get(const std::string& key);

  double number(const std::string& key, double fallback, double min = -std::numeric_limits<double>::infinity(),
                double max = std::numeric_limits<double>::infinity(), bool min_exclusive = false);
  long long integer(const std::string& key, long long fallback, long long min, long long max);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key, const std::string& fallback);
  /// A string that must be one of `choices`.
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& choices);
  /// Three numbers, each within +-kMaxVectorComponent: every 3-vector of a scene ends up in 32-bit
  /// floats (the renderer's vertices and uniforms, the particle store), where 1e39 is infinite.
  std::array<double, 3> vec3(const std::string& key, std::array<double, 3> fallback);
  /// The same with each component in [min, max].
  std::array<double, 3> vec3(const std::string& key, std::array<double, 3> fallback, double min, double max);
  /// The same with a range shared with the engine's validation (simreel/sim/ranges.hpp), so the
  /// loader and the engine reject the same values; messages are those of the overloads above.
  double number(const std::string& key, double fallback, const sim::Range& range) {
    return number(key, fallback, range.min, range.max, range.min_open);
  }
  long long integer(const std::string& key, long long fallback, const sim::IntRange& range) {
    return integer(key, fallback, range.min, range.max);
  }
  std::vector<double> numbers(const std::string& key, std::vector<double> fallback, std::size_t count,
                              const sim::Range& range) {
    return numbers(key, std::move(fallback), count, range.min, range.max, range.min_open);
  }
  /// RGB (3 numbers) or RGBA (4 numbers) in [0, 1]; alpha defaults to 1.
  std::array<double, 4> color(const std::string& key, std::array<double, 4> fallback);
  /// Fixed-length array of numbers each in [min, max].
  std::vector<double> numbers(const std::string& key, std::vector<double> fallback, std::size_t count,
                              double min, double max, bool min_exclusive = false);

  /// Records `schema` for `key` in the thread's KeyLog, if one is installed.
  void record(const std::string& key, const json& schema) const;

  /// Adds an error at this object's key.
  void error(const std::string& key, const std::string& expected, const json& found);
  void error_at(const std::string& pointer, const std::string& message);

  /// Reports keys present but never read, with the closest known key as a hint.
  void finish();

 private:
  const json& object_;
  std::string pointer_;
  std::string file_;
  std::vector<std::string>& errors_;
  std::set<std::string> known_;
};

}  // namespace simreel::app
