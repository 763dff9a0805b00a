#pragma once
// Binary writer and reader of the engine state (World::save_state / load_state; private to sim/).
// The format is a sequence of sections, each a 4-byte tag, a 64-bit byte count and its body, so a
// reader checks that every section is the one it expects and ends where its size says; values
// are the machine's bytes (little-endian on every platform simreel builds on), arrays a 64-bit
// count then the elements. Structs with padding are written field by field, so the bytes of a
// state depend on its values only (a cache resumed after a kill is byte-identical).
//
// Sections are per subsystem (state_snapshot.cpp): adding a subsystem adds a section and bumps
// kStateFormat.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "simreel/sim/random.hpp"
#include "simreel/sim/state_error.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// Version of the section layout; World::load_state refuses any other.
inline constexpr std::uint32_t kStateFormat = 4;  // 2: joints; 3: particle sleep; 4: an awake particle's rest position is where its last step ended (the motion test of update_rest())

/// Appends to a byte string (reused from frame to frame: no allocation once grown).
class StateWriter {
 public:
  explicit StateWriter(std::string& out) : out_(out) {}

  /// Opens section `tag` (4 characters); end() writes its size.
  void begin(const char (&tag)[5]) {
    out_.append(tag, 4);
    open_ = out_.size();
    value(std::uint64_t(0));
  }
  void end() {
    const std::uint64_t n = out_.size() - open_ - sizeof(std::uint64_t);
    std::memcpy(out_.data() + open_, &n, sizeof n);
  }
  /// A value without padding (arithmetic, Vec3, Quat, Mat3).
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_destructible_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  /// The first n elements of an array (element type without padding), count first.
  template <class Array>
  void array(const Array& a, std::size_t n) {
    value(std::uint64_t(n));
    if (n > 0) out_.append(reinterpret_cast<const char*>(a.data()), n * sizeof(typename Array::value_type));
  }
  template <class Array>
  void array(const Array& a) {
    array(a, a.size());
  }
  void rng(const Rng& r) {
    const Rng::State s = r.state();
    for (std::uint64_t w : s.s) value(w);
    value(s.has_cached ? s.cached : 0.0);
    value(std::uint8_t(s.has_cached));
  }

 private:
  std::string& out_;
  std::size_t open_ = 0;
};

using sim::StateError;

/// Whether every scalar of v is finite (a float, double, Vec3, Mat3 or Quat).
inline bool finite_value(double v) { return std::isfinite(v); }
inline bool finite_value(const Quat& q) { return q.coeffs().allFinite(); }
template <class Derived>
bool finite_value(const Eigen::DenseBase<Derived>& m) {
  return m.allFinite();
}

/// Refuses a loaded value that a step could not have written: NaN or infinite. The checksum of a
/// cache frame only proves the bytes are the ones written; a hand-edited or corrupt frame with a
/// recomputed checksum otherwise loaded and ended a run one step later as "simulation diverged"
/// (exit 1) instead of naming the state.
template <class T>
void require_finite(const T& v, const std::string& what) {
  if (!finite_value(v)) throw StateError("state: " + what + " is not finite");
}
/// The same over the first n elements of an array, naming the first bad element's index.
template <class Array>
void require_finite(const Array& a, std::size_t n, const std::string& what) {
  for (std::size_t i = 0; i < n; ++i)
    if (!finite_value(a[i]))
      throw StateError("state: " + what + ": value " + std::to_string(i) + " of " +
                       std::to_string(n) + " is not finite");
}

/// Reads what StateWriter wrote; every read is bounds-checked (a truncated or corrupt state
/// throws StateError, it never reads past the end).
class StateReader {
 public:
  explicit StateReader(std::string_view in) : in_(in) {}

  void begin(const char (&tag)[5]) {
    need(4 + sizeof(std::uint64_t), tag);
    if (std::memcmp(in_.data() + pos_, tag, 4) != 0)
      throw StateError(std::string("state: expected section '") + tag + "', found '" +
                       printable(in_.substr(pos_, 4)) + "'");
    pos_ += 4;
    const auto n = value<std::uint64_t>();
    if (n > in_.size() - pos_)
      throw StateError(std::string("state: section '") + tag + "' is truncated (" +
                       std::to_string(n) + " bytes declared, " + std::to_string(in_.size() - pos_) +
                       " left)");
    end_ = pos_ + n;
    tag_ = tag;
  }
  void end() {
    if (pos_ != end_)
      throw StateError("state: section '" + tag_ + "' has " + std::to_string(end_ - pos_) +
                       " unread bytes (written by another layout)");
    end_ = 0;
  }
  template <class T>
  T value() {
    T v;
    need(sizeof v, tag_.c_str());
    std::memcpy(static_cast<void*>(&v), in_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  template <class T>
  void value(T& v) {
    v = value<T>();
  }
  /// Reads an array into `a` (resized; within its capacity when reserved); more than `max`
  /// elements is an error naming `what`.
  template <class Array>
  void array(Array& a, std::size_t max, const char* what) {
    using T = typename Array::value_type;
    const auto n = value<std::uint64_t>();
    if (n > max)
      throw StateError(std::string("state: ") + what + " holds " + std::to_string(n) +
                       " elements, this world has room for " + std::to_string(max));
    need(n * sizeof(T), what);
    a.resize(std::size_t(n));
    if (n > 0) std::memcpy(static_cast<void*>(a.data()), in_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
  }
  /// Reads a count of records that take at least `min_bytes` each: more than the bytes left in
  /// the section could hold is an error naming `what`, before the caller allocates them (a
  /// corrupt count of 2^32 contact manifolds asked for a terabyte).
  std::size_t records(std::size_t min_bytes, const char* what) {
    const auto n = value<std::uint64_t>();
    const std::size_t left = (end_ != 0 ? end_ : in_.size()) - pos_;
    if (n > left / min_bytes)
      throw StateError(std::string("state: ") + std::to_string(n) + " " + what + " declared, the " +
                       std::to_string(left) + " bytes left in section '" + tag_ + "' hold at most " +
                       std::to_string(left / min_bytes));
    return std::size_t(n);
  }
  /// Reads a count that must equal `expected` (an object count fixed by the scene).
  void count(std::uint64_t expected, const char* what) {
    const auto n = value<std::uint64_t>();
    if (n != expected)
      throw StateError(std::string("state: ") + std::to_string(n) + " " + what + ", this world has " +
                       std::to_string(expected));
  }
  void rng(Rng& r) {
    Rng::State s{};
    for (std::uint64_t& w : s.s) value(w);
    value(s.cached);
    s.has_cached = value<std::uint8_t>() != 0;
    r.set_state(s);
  }
  [[nodiscard]] bool done() const { return pos_ == in_.size(); }
  [[nodiscard]] std::size_t position() const { return pos_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (n > in_.size() - pos_ || (end_ != 0 && pos_ + n > end_))
      throw StateError(std::string("state: truncated in '") + what + "'");
  }
  static std::string printable(std::string_view s) {
    std::string o;
    for (char c : s) o += (c >= 32 && c < 127) ? c : '?';
    return o;
  }
  std::string_view in_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
  std::string tag_;
};

}  // namespace simreel::sim::detail
