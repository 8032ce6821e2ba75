// What a config file must look like before OpenCV's YAML parser sees it (private to the
// library): that parser recurses once per level of nesting (200 000 levels overflow the stack),
// reads integers as 32-bit `int` (wrapping larger ones), and loops or reads out of bounds on a few
// layouts.
#pragma once

#include <cstddef>
#include <string>

namespace multislit {

constexpr std::size_t kMaxYamlBytes = 64u << 20;  ///< [bytes]
constexpr int kMaxYamlNesting = 64;  ///< levels of [ ] and { }; block collections begun on a line
constexpr std::size_t kMaxYamlIndent = 1024;  ///< leading spaces of a line (block nesting)

/// What in `text` OpenCV's YAML parser would overflow its stack on, read wrongly, or is known to
/// fail on (fuzz/), "" when nothing:
/// - nesting deeper than the limits above, counted as the parser nests: flow brackets outside
///   quoted strings and comments, and block collections ("- ", "key:") begun on one line
///   (`- - - 1`). A quote begins a string only where a value begins, as the parser reads it: the
///   apostrophe of `camera_id: it's` is a letter;
/// - an integer outside [-2^31, 2^31 - 1] (the parser would wrap 4294968592 to 1296), or one
///   with a leading 0 (it would read 010 as octal 8);
/// - a layout it fails on: a NUL byte, a first key not at the start of a line, a second
///   document, a document end "...", a line starting with ':'.
std::string yamlShapeProblem(const std::string& text);

}  // namespace multislit
