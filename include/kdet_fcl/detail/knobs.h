#pragma once
// The library's environment knobs (KDET_FCL_*): one strict parse for all of them, shared by the
// CPU backend, the CUDA backend and the benchmarks' LBVH baseline.
//
// A knob that is unset or empty means its default. Any other value must be one the knob
// accepts; a value it does not accept ("yes", "abc", "8x", "-1", a number out of its range)
// throws InvalidInputError naming the variable, its value and what it accepts. Nothing is
// silently read as something else: a misspelt value would otherwise quietly run another
// configuration (ROUND_CANDIDATES=abc read as 0 meant "no limit" on the candidate buffer).

#include <cstdint>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <cstring>
#include <string>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>  // environ
#endif

#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace detail {

/// The value of the environment variable `name`, or nullptr when it is unset or empty.
inline const char* knobText(const char* name) {
  const char* e = std::getenv(name);
  return (e != nullptr && *e != 0) ? e : nullptr;
}

/// Whether some environment variable's name starts with `prefix` ("KDET_FCL_CUDA_"): one pass
/// over the environment, so that a check of every knob (cuda::checkKnobs) costs nothing
/// measurable where none is set. Where the environment cannot be listed, true.
inline bool someKnobSet(const char* prefix) {
#if defined(__unix__) || defined(__APPLE__)
  const std::size_t n = std::strlen(prefix);
  for (char** e = environ; e != nullptr && *e != nullptr; ++e)
    if (std::strncmp(*e, prefix, n) == 0) return true;
  return false;
#else
  (void)prefix;
  return true;
#endif
}

/// Appends to `text` each environment entry ("NAME=value") whose name starts with `prefix`, with
/// a '\n' after each, in the environment's order: the knobs' whole setting, which a check of
/// every knob can compare with the setting it last found good (cuda::checkKnobs). Returns false
/// where the environment cannot be listed (`text` unchanged).
inline bool appendKnobEntries(const char* prefix, std::string& text) {
#if defined(__unix__) || defined(__APPLE__)
  const std::size_t n = std::strlen(prefix);
  for (char** e = environ; e != nullptr && *e != nullptr; ++e)
    if (std::strncmp(*e, prefix, n) == 0) text.append(*e).push_back('\n');
  return true;
#else
  (void)prefix;
  (void)text;
  return false;
#endif
}

/// Throws the error of a knob whose value `text` is not one it accepts (`accepts` says what is).
[[noreturn]] inline void badKnob(const char* name, const char* text, const std::string& accepts) {
  throw InvalidInputError(std::string(name) + "='" + text + "': expected " + accepts +
                          " (unset or empty: the default)");
}

/// Parses `text` as a whole decimal number: digits only (no sign, no spaces), at most 2^64 - 1.
/// Returns false for anything else.
inline bool parseWholeNumber(const char* text, std::uint64_t* value) {
  if (text == nullptr || *text == 0) return false;
  std::uint64_t v = 0;
  for (const char* c = text; *c != 0; ++c) {
    if (*c < '0' || *c > '9') return false;
    const std::uint64_t d = static_cast<std::uint64_t>(*c - '0');
    if (v > (std::numeric_limits<std::uint64_t>::max() - d) / 10) return false;
    v = v * 10 + d;
  }
  *value = v;
  return true;
}

/// An on/off knob: "0" off, "1" on, unset or empty `otherwise` (the choice's own rule).
inline bool switchKnob(const char* name, bool otherwise) {
  const char* e = knobText(name);
  if (e == nullptr) return otherwise;
  if (e[0] == '0' && e[1] == 0) return false;
  if (e[0] == '1' && e[1] == 0) return true;
  badKnob(name, e, "0 (off) or 1 (on)");
}

/// A whole-number knob within [lo, hi]; unset or empty: `otherwise`.
inline std::uint64_t numberKnob(const char* name, std::uint64_t lo, std::uint64_t hi,
                                std::uint64_t otherwise) {
  const char* e = knobText(name);
  if (e == nullptr) return otherwise;
  std::uint64_t v = 0;
  if (!parseWholeNumber(e, &v) || v < lo || v > hi)
    badKnob(name, e, "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
  return v;
}

/// A knob that takes one of the numbers `allowed`; unset or empty: `otherwise`.
inline std::uint64_t choiceKnob(const char* name, std::initializer_list<std::uint64_t> allowed,
                                std::uint64_t otherwise) {
  const char* e = knobText(name);
  if (e == nullptr) return otherwise;
  std::uint64_t v = 0;
  const bool number = parseWholeNumber(e, &v);
  std::string list;
  for (const std::uint64_t a : allowed) {
    if (number && v == a) return v;
    list += (list.empty() ? "" : ", ") + std::to_string(a);
  }
  badKnob(name, e, "one of " + list);
}

/// A knob that takes one of the words `allowed`; returns the index of its word, or `otherwise`
/// when it is unset or empty.
inline int wordKnob(const char* name, std::initializer_list<const char*> allowed, int otherwise) {
  const char* e = knobText(name);
  if (e == nullptr) return otherwise;
  int i = 0;
  std::string list;
  for (const char* a : allowed) {
    if (std::string(a) == e) return i;
    list += (list.empty() ? "" : ", ") + std::string(a);
    ++i;
  }
  badKnob(name, e, "one of " + list);
}

}  // namespace detail
}  // namespace kdet_fcl
