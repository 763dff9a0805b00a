#include "json_reader.hpp"
#include "simreel/sim/ranges.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace simreel::app {

namespace {

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i) out += '\n';
    out += lines[i];
  }
  return out;
}

std::string type_name(const json& v) {
  switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "boolean";
    case json::value_t::string: return "string";
    case json::value_t::array: return "array";
    case json::value_t::object: return "object";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: return "number";
    default: return "value";
  }
}

struct NumberAt {
  std::size_t line = 1;
  std::size_t col = 1;
  std::string number;
};

/// The first number token of `text` (outside strings) that does not fit a double.
NumberAt overflowing_number(const std::string& text) {
  NumberAt at;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
        ++at.col;
      } else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      std::size_t end = i;
      while (end < text.size() && std::strchr("0123456789+-.eE", text[end]) != nullptr && text[end] != '\0') ++end;
      const std::string token = text.substr(i, end - i);
      if (!std::isfinite(std::strtod(token.c_str(), nullptr))) {
        at.number = token.size() > 40 ? token.substr(0, 37) + "..." : token;
        return at;
      }
      at.col += end - 1 - i;
      i = end - 1;
    }
    if (i < text.size() && text[i] == '\n') {
      ++at.line;
      at.col = 1;
    } else {
      ++at.col;
    }
  }
  return at;
}

}  // namespace

SceneError::SceneError(std::vector<std::string> messages)
    : std::runtime_error(join_lines(messages)), messages_(std::move(messages)) {}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string pointer_token(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

std::string describe(const json& v) {
  if (v.is_object()) return "an object";
  if (v.is_array()) return "an array of " + std::to_string(v.size());
  std::string text = v.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text + " (" + type_name(v) + ")";
}

json parse_json_text(const std::string& text, const std::string& file) {
  try {
    return json::parse(text);
  } catch (const json::out_of_range&) {
    // nlohmann's "number overflow" (e.g. 1e400) carries no position: find the number.
    auto [line, col, number] = overflowing_number(text);
    throw SceneError(file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": number " + number +
                     " is out of range, expected a finite number (at most about 1.8e308)");
  } catch (const json::parse_error& e) {
    // nlohmann reports a byte offset; users need line and column.
    std::size_t line = 1, col = 1;
    const std::size_t end = std::min<std::size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size());
    for (std::size_t i = 0; i < end; ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    std::string reason = e.what();
    // Strip nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: " prefix.
    if (auto pos = reason.find(": "); pos != std::string::npos) reason = reason.substr(pos + 2);
    if (auto pos = reason.find("syntax error while parsing value - "); pos != std::string::npos)
      reason = reason.substr(pos + 35);
    throw SceneError(file + ":" + std::to_string(line) + ":" + std::to_string(col) +
                     ": invalid JSON: " + reason);
  }
}

std::string read_regular_file(const std::filesystem::path& path, const std::string& what, std::uintmax_t limit) {
  const std::string file = path.string();
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) throw SceneError(file + ": cannot read " + what + ": no such file");
    throw SceneError(file + ": cannot read " + what + ": " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) throw SceneError(file + ": cannot read " + what + ": is a directory, expected a JSON file");
  // A FIFO would block, /dev/zero never ends: only regular files are read.
  if (!S_ISREG(st.st_mode))
    throw SceneError(file + ": cannot read " + what + ": not a regular file (a device, FIFO or socket), expected a JSON file");
  if (std::uintmax_t(st.st_size) > limit)
    throw SceneError(file + ": cannot read " + what + ": " + std::to_string(st.st_size) + " bytes, expected at most " +
                     std::to_string(limit) + " (the JSON size limit)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(file + ": cannot read " + what + ": permission denied or unreadable");
  // Read at most limit + 1 bytes: a file that grows while read is still bounded.
  std::string text(std::size_t(st.st_size), '\0');
  in.read(text.data(), std::streamsize(text.size()));
  text.resize(std::size_t(in.gcount()));
  char extra[4096];
  while (in.read(extra, sizeof extra) || in.gcount() > 0) {
    text.append(extra, std::size_t(in.gcount()));
    if (text.size() > limit)
      throw SceneError(file + ": cannot read " + what + ": more than " + std::to_string(limit) +
                       " bytes (the JSON size limit)");
  }
  return text;
}

json parse_json_file(const std::filesystem::path& path, const std::string& what) {
  return parse_json_text(read_regular_file(path, what, kMaxJsonBytes), path.string());
}

std::optional<long long> parse_integer(std::string_view text, long long min, long long max) {
  long long v = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (text.empty() || text.front() == '+' || ec != std::errc() || ptr != end || v < min || v > max) return std::nullopt;
  return v;
}

std::optional<std::pair<long long, long long>> parse_pair(std::string_view text, char separator, long long min,
                                                          long long max) {
  const auto sep = text.find(separator);
  if (sep == std::string_view::npos) return std::nullopt;
  const auto a = parse_integer(text.substr(0, sep), min, max);
  const auto b = parse_integer(text.substr(sep + 1), min, max);
  if (!a || !b) return std::nullopt;
  return std::pair{*a, *b};
}

void apply_override(json& doc, const std::string& assignment, const std::string& file) {
  const auto eq = assignment.find('=');
  const std::string where = "--set " + assignment;
  if (eq == std::string::npos || eq == 0)
    throw SceneError(where + ": expected POINTER=VALUE, e.g. /emitters/0/rate=500");
  const std::string ptr_text = assignment.substr(0, eq);
  const std::string value_text = assignment.substr(eq + 1);
  if (ptr_text.front() != '/')
    throw SceneError(where + ": expected a JSON pointer starting with '/', found \"" + ptr_text + "\"");
  json::json_pointer ptr;
  try {
    ptr = json::json_pointer(ptr_text);
  } catch (const json::exception& e) {
    throw SceneError(where + ": invalid JSON pointer \"" + ptr_text + "\"");
  }
  json value;
  try {
    value = json::parse(value_text);
  } catch (const json::parse_error&) {
    value = value_text;  // a bare word is a string
  } catch (const json::out_of_range&) {
    throw SceneError(where + ": " + ptr_text + ": number " + value_text +
                     " is out of range, expected a finite number (at most about 1.8e308)");
  }
  if (doc.contains(ptr)) {
    doc[ptr] = value;
    return;
  }
  const json::json_pointer parent = ptr.parent_pointer();
  if (doc.contains(parent) && doc[parent].is_object()) {
    doc[ptr] = value;  // a new key; the schema check rejects unknown ones
    return;
  }
  // Keys of objects the scene leaves out (--set /simulation/max_step=0.001 on a scene without a
  // "simulation" block): the objects are made, as a user writing them would, and the schema check
  // rejects a misspelt one. A missing array element (/emitters/3/rate) is not made up.
  {
    json::json_pointer base = parent;
    std::vector<std::string> missing;
    while (!base.empty() && !doc.contains(base)) {
      missing.push_back(base.back());
      base.pop_back();
    }
    const bool keys = std::none_of(missing.begin(), missing.end(), [](const std::string& t) {
      return !t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
    });
    if (keys && doc[base].is_object() && !missing.empty() && !ptr.back().empty()) {
      doc[ptr] = value;  // nlohmann's operator[] makes the missing objects on the way
      return;
    }
  }
  throw SceneError(file + ": " + ptr_text + ": --set names nothing in the scene (no value at " +
                   ptr_text + " and " + (parent.empty() ? "/" : parent.to_string()) +
                   " is not an object)");
}

namespace {
thread_local KeyLog* g_key_log = nullptr;

/// {"minimum": min, "maximum": max} with open and infinite ends left out or made exclusive.
void add_range(json& schema, double min, double max, bool min_exclusive) {
  if (std::isfinite(min)) schema[min_exclusive ? "exclusiveMinimum" : "minimum"] = min;
  if (std::isfinite(max)) schema["maximum"] = max;
}
}  // namespace

KeyLog::Scope::Scope(KeyLog& log) : previous_(g_key_log) { g_key_log = &log; }
KeyLog::Scope::~Scope() { g_key_log = previous_; }
KeyLog* KeyLog::current() { return g_key_log; }

std::string KeyLog::normalise(const std::string& pointer) {
  std::string out;
  std::size_t i = 0;
  while (i < pointer.size()) {
    const std::size_t next = pointer.find('/', i + 1);
    const std::string token = pointer.substr(i + 1, (next == std::string::npos ? pointer.size() : next) - i - 1);
    const bool index = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos;
    out += "/" + (index ? std::string("*") : token);
    if (next == std::string::npos) break;
    i = next;
  }
  return out;
}

void KeyLog::add(const std::string& pointer, const std::string& key, const json& schema) {
  const std::string object = normalise(pointer);
  auto obj = std::find_if(objects_.begin(), objects_.end(), [&](const auto& o) { return o.first == object; });
  if (obj == objects_.end()) {
    objects_.push_back({object, {}});
    obj = objects_.end() - 1;
  }
  auto k = std::find_if(obj->second.begin(), obj->second.end(), [&](const auto& e) { return e.first == key; });
  if (k == obj->second.end()) {
    obj->second.push_back({key, {schema}});
    return;
  }
  auto& schemas = k->second;
  const bool raw = schema.empty();
  if (raw) return;  // a typed schema (or the same raw one) is already there
  schemas.erase(std::remove_if(schemas.begin(), schemas.end(), [](const json& s) { return s.empty(); }),
                schemas.end());
  if (std::find(schemas.begin(), schemas.end(), schema) != schemas.end()) return;
  // The same kind of value read with other bounds or another default (a range that depends on
  // other keys, such as a pin's row in [0, rows - 1]): one schema with the widest bounds.
  for (json& s : schemas) {
    json a = s, b = schema;
    for (json* x : {&a, &b})
      for (const char* k : {"default", "minimum", "maximum", "exclusiveMinimum"}) x->erase(k);
    if (a != b) continue;
    if (s.value("default", json()) != schema.value("default", json())) s.erase("default");
    for (const char* k : {"minimum", "exclusiveMinimum"}) {
      if (!s.contains(k)) continue;
      if (!schema.contains(k)) s.erase(k);
      else s[k] = std::min(s[k].get<double>(), schema[k].get<double>());
    }
    if (s.contains("maximum")) {
      if (!schema.contains("maximum")) s.erase("maximum");
      else s["maximum"] = std::max(s["maximum"].get<double>(), schema["maximum"].get<double>());
    }
    return;
  }
  schemas.push_back(schema);
}

std::vector<std::string> KeyLog::keys(const std::string& pointer) const {
  std::vector<std::string> out;
  const std::string object = normalise(pointer);
  for (const auto& [o, keys] : objects_)
    if (o == object)
      for (const auto& k : keys) out.push_back(k.first);
  return out;
}

void ObjectReader::record(const std::string& key, const json& schema) const {
  if (g_key_log != nullptr) g_key_log->add(pointer_, key, schema);
}

ObjectReader::ObjectReader(const json& object, std::string pointer, std::string file,
                           std::vector<std::string>& errors)
    : object_(object), pointer_(std::move(pointer)), file_(std::move(file)), errors_(errors) {}

bool ObjectReader::has(const std::string& key) const { return object_.contains(key); }

const json* ObjectReader::get(const std::string& key) {
  known_.insert(key);
  record(key, json::object());
  auto it = object_.find(key);
  return it == object_.end() ? nullptr : &*it;
}

void ObjectReader::error(const std::string& key, const std::string& expected, const json& found) {
  errors_.push_back(file_ + ": " + pointer(key) + ": expected " + expected + ", found " + describe(found));
}

void ObjectReader::error_at(const std::string& ptr, const std::string& message) {
  errors_.push_back(file_ + ": " + (ptr.empty() ? "/" : ptr) + ": " + message);
}

double ObjectReader::number(const std::string& key, double fallback, double min, double max,
                            bool min_exclusive) {
  if (g_key_log != nullptr) {
    json schema = {{"type", "number"}};
    add_range(schema, min, max, min_exclusive);
    if (std::isfinite(fallback) && std::abs(fallback) < 1e299) schema["default"] = fallback;
    record(key, schema);
  }
  const json* v = get(key);
  if (!v) return fallback;
  std::string range = "a number";
  if (std::isfinite(min) && std::isfinite(max))
    range += std::string(" in ") + (min_exclusive ? "(" : "[") + sim::format_number(min) + ", " + sim::format_number(max) + "]";
  else if (std::isfinite(min))
    range += (min_exclusive ? " > " : " >= ") + sim::format_number(min);
  else if (std::isfinite(max))
    range += " <= " + sim::format_number(max);
  if (!v->is_number()) {
    error(key, range, *v);
    return fallback;
  }
  const double x = v->get<double>();
  if (!std::isfinite(x) || x < min || x > max || (min_exclusive && x == min)) {
    error(key, range, *v);
    return fallback;
  }
  return x;
}

long long ObjectReader::integer(const std::string& key, long long fallback, long long min, long long max) {
  if (g_key_log != nullptr) record(key, {{"type", "integer"}, {"minimum", min}, {"maximum", max}, {"default", fallback}});
  const json* v = get(key);
  if (!v) return fallback;
  const std::string expected = "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  if (!v->is_number_integer() && !(v->is_number_float() && std::floor(v->get<double>()) == v->get<double>())) {
    error(key, expected, *v);
    return fallback;
  }
  // Integers are compared as integers; a float only below 2^63 (double(LLONG_MAX) rounds up to
  // 2^63, which no long long holds), so no cast ever overflows.
  long long x = 0;
  bool in_range = false;
  if (v->is_number_unsigned()) {
    const auto u = v->get<std::uint64_t>();
    in_range = u <= std::uint64_t(std::numeric_limits<long long>::max());
    x = in_range ? static_cast<long long>(u) : 0;
  } else if (v->is_number_integer()) {
    x = v->get<long long>();
    in_range = true;
  } else {
    const double d = v->get<double>();
    in_range = d >= -0x1p63 && d < 0x1p63;
    x = in_range ? static_cast<long long>(d) : 0;
  }
  if (!in_range || x < min || x > max) {
    error(key, expected, *v);
    return fallback;
  }
  return x;
}

bool ObjectReader::boolean(const std::string& key, bool fallback) {
  if (g_key_log != nullptr) record(key, {{"type", "boolean"}, {"default", fallback}});
  const json* v = get(key);
  if (!v) return fallback;
  if (!v->is_boolean()) {
    error(key, "true or false", *v);
    return fallback;
  }
  return v->get<bool>();
}

std::string ObjectReader::string(const std::string& key, const std::string& fallback) {
  if (g_key_log != nullptr) record(key, {{"type", "string"}, {"default", fallback}});
  const json* v = get(key);
  if (!v) return fallback;
  if (!v->is_string()) {
    error(key, "a string", *v);
    return fallback;
  }
  return v->get<std::string>();
}

std::string ObjectReader::choice(const std::string& key, const std::string& fallback,
                                 const std::vector<std::string>& choices) {
  std::string expected = "one of";
  for (std::size_t i = 0; i < choices.size(); ++i) expected += (i ? ", \"" : " \"") + choices[i] + "\"";
  if (g_key_log != nullptr) {
    json schema = {{"enum", choices}};
    if (!fallback.empty()) schema["default"] = fallback;
    record(key, schema);
  }
  const json* v = get(key);
  if (!v) return fallback;
  if (!v->is_string() || std::find(choices.begin(), choices.end(), v->get<std::string>()) == choices.end()) {
    error(key, expected, *v);
    return fallback;
  }
  return v->get<std::string>();
}

std::vector<double> ObjectReader::numbers(const std::string& key, std::vector<double> fallback,
                                          std::size_t count, double min, double max, bool min_exclusive) {
  if (g_key_log != nullptr) {
    json item = {{"type", "number"}};
    add_range(item, min, max, min_exclusive);
    json schema = {{"type", "array"}, {"items", item}, {"minItems", count}, {"maxItems", count}};
    if (fallback.size() == count) schema["default"] = fallback;
    record(key, schema);
  }
  const json* v = get(key);
  if (!v) return fallback;
  std::string expected = "an array of " + std::to_string(count) + " numbers";
  if (std::isfinite(min) || std::isfinite(max)) {
    expected += " each ";
    if (std::isfinite(min) && std::isfinite(max))
      expected += std::string("in ") + (min_exclusive ? "(" : "[") + sim::format_number(min) + ", " + sim::format_number(max) + "]";
    else if (std::isfinite(min))
      expected += (min_exclusive ? "> " : ">= ") + sim::format_number(min);
    else
      expected += "<= " + sim::format_number(max);
  }
  if (!v->is_array() || v->size() != count) {
    error(key, expected, *v);
    return fallback;
  }
  std::vector<double> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    const json& e = (*v)[i];
    const bool ok = e.is_number() && std::isfinite(e.get<double>()) && e.get<double>() >= min &&
                    e.get<double>() <= max && !(min_exclusive && e.get<double>() == min);
    if (!ok) {
      errors_.push_back(file_ + ": " + pointer(key) + "/" + std::to_string(i) + ": expected " + expected +
                        ", found " + describe(e));
      return fallback;
    }
    out[i] = e.get<double>();
  }
  return out;
}

std::array<double, 3> ObjectReader::vec3(const std::string& key, std::array<double, 3> fallback) {
  return vec3(key, fallback, -kMaxVectorComponent, kMaxVectorComponent);
}

std::array<double, 3> ObjectReader::vec3(const std::string& key, std::array<double, 3> fallback, double min,
                                         double max) {
  auto v = numbers(key, {fallback[0], fallback[1], fallback[2]}, 3, min, max);
  return {v[0], v[1], v[2]};
}

std::array<double, 4> ObjectReader::color(const std::string& key, std::array<double, 4> fallback) {
  if (g_key_log != nullptr)
    record(key, {{"type", "array"},
                 {"items", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}}},
                 {"minItems", 3},
                 {"maxItems", 4},
                 {"default", fallback}});
  const json* v = get(key);
  if (!v) return fallback;
  const std::string expected = "a color [r, g, b] or [r, g, b, a] with each in [0, 1]";
  if (!v->is_array() || (v->size() != 3 && v->size() != 4)) {
    error(key, expected, *v);
    return fallback;
  }
  std::array<double, 4> out{0, 0, 0, 1};
  for (std::size_t i = 0; i < v->size(); ++i) {
    const json& e = (*v)[i];
    if (!e.is_number() || !(e.get<double>() >= 0.0 && e.get<double>() <= 1.0)) {
      errors_.push_back(file_ + ": " + pointer(key) + "/" + std::to_string(i) + ": expected " + expected +
                        ", found " + describe(e));
      return fallback;
    }
    out[i] = e.get<double>();
  }
  return out;
}

void ObjectReader::finish() {
  for (auto it = object_.begin(); it != object_.end(); ++it) {
    if (known_.count(it.key())) continue;
    std::string hint;
    std::size_t best = std::string::npos;
    for (const auto& k : known_) {
      const std::size_t d = edit_distance(it.key(), k);
      if (d < best) {
        best = d;
        hint = k;
      }
    }
    std::string msg = file_ + ": " + pointer(it.key()) + ": unknown key \"" + it.key() + "\"";
    if (!hint.empty() && best <= std::max<std::size_t>(2, hint.size() / 3)) msg += "; did you mean \"" + hint + "\"?";
    else if (!known_.empty()) {
      msg += "; expected one of:";
      for (const auto& k : known_) msg += " " + k;
    }
    errors_.push_back(msg);
  }
}

}  // namespace simreel::app
