// The checks of yaml_shape.h. The scan follows OpenCV's YAML parser (persistence_yml.cpp) where
// it nests, and errs towards counting more where the two could differ.
#include "yaml_shape.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

namespace multislit {

namespace {

bool printable(char c) { return static_cast<unsigned char>(c) >= ' '; }
bool digit(char c) { return c >= '0' && c <= '9'; }

/// Where the parser reads a number: a digit, a sign before a digit or '.', '.' before a letter.
bool startsNumber(std::string_view s, std::size_t at) {
  const char c = s[at], d = at + 1 < s.size() ? s[at + 1] : '\0';
  return digit(c) || ((c == '-' || c == '+') && (digit(d) || d == '.')) ||
         (c == '.' && std::isalnum(static_cast<unsigned char>(d)));
}

/// Past the quoted string that starts at `at`: '' escapes a quote in '...', a backslash the next
/// character in "...", and a string ends with its line (the parser refuses it there).
std::size_t quotedEnd(std::string_view s, std::size_t at) {
  const char quote = s[at];
  for (std::size_t k = at + 1; k < s.size(); ++k) {
    if (!printable(s[k])) return k;
    if (quote == '"' && s[k] == '\\') {
      ++k;
    } else if (s[k] == quote) {
      if (quote == '\'' && k + 1 < s.size() && s[k + 1] == '\'')
        ++k;
      else
        return k + 1;
    }
  }
  return s.size();
}

/// The line as a message shows it: trimmed, at most 60 characters.
std::string quoted(std::string_view s) {
  const std::size_t a = s.find_first_not_of(" \r");
  const std::size_t b = s.find_last_not_of(" \r");
  const std::string_view t =
      a == std::string_view::npos ? std::string_view() : s.substr(a, b - a + 1);
  return "'" + std::string(t.substr(0, 60)) + (t.size() > 60 ? "...'" : "'");
}

/// The nesting and integers of a file, line by line.
class ShapeScan {
 public:
  void line(std::string_view s, std::size_t number);
  std::string problem() const;

 private:
  enum class Next { Value, FirstKey, Key, After };  ///< what the parser reads next
  std::size_t token(std::string_view s, std::size_t at, int& begun);
  std::size_t keyOrPlain(std::string_view s, std::size_t at, bool key, int& begun);
  void checkInteger(std::string_view s, std::size_t at);
  void open(char bracket);

  std::string stack_;  ///< open flow collections, '[' or '{'
  Next next_ = Next::Key;
  std::size_t deepest_ = 0, widest_ = 0, most_begun_ = 0, most_begun_line_ = 0;
  std::size_t number_ = 0;
  std::string integer_problem_;
};

void ShapeScan::line(std::string_view s, std::size_t number) {
  number_ = number;
  std::size_t at = s.find_first_not_of(" \r");
  if (at == std::string_view::npos || s[at] == '#') return;
  if (stack_.empty()) {  // a block line: a key, "- ", a flow collection or a value
    widest_ = std::max(widest_, at);
    next_ = Next::Key;
  }
  int begun = 0;
  while (at < s.size()) at = token(s, at, begun);
  if (static_cast<std::size_t>(begun) > most_begun_) {
    most_begun_ = static_cast<std::size_t>(begun);
    most_begun_line_ = number;
  }
}

void ShapeScan::open(char bracket) {
  stack_ += bracket;
  deepest_ = std::max(deepest_, stack_.size());
  next_ = bracket == '{' ? Next::FirstKey : Next::Value;
}

/// Reads the token at `at` (not a space); returns where the next one may start.
std::size_t ShapeScan::token(std::string_view s, std::size_t at, int& begun) {
  const char c = s[at];
  const bool flow = !stack_.empty();
  if (c == ' ' || !printable(c)) return at + 1;
  if (c == '#') return s.size();  // a comment
  if (next_ == Next::After) {     // after a value: a separator, a closing bracket or junk
    next_ = c == ',' && flow && stack_.back() == '{' ? Next::Key : Next::Value;
    if (c == ',' || c == ':') return at + 1;
    if (c != ']' && c != '}') return at;  // the parser refuses it; read it as a value
  }
  if (c == ']' || c == '}') {
    // A flow map's key after ',' is read raw up to ':', brackets too.
    if (flow && next_ == Next::Key) return keyOrPlain(s, at, true, begun);
    if (flow) stack_.pop_back();
    next_ = Next::After;
    return at + 1;
  }
  if (flow && (next_ == Next::Key || next_ == Next::FirstKey))
    return keyOrPlain(s, at, true, begun);
  if (c == '[' || c == '{') {
    open(c);
    return at + 1;
  }
  if (!flow && c == '-' && !startsNumber(s, at)) {  // a block sequence's item
    ++begun;
    next_ = Next::Value;
    return at + 1;
  }
  if (startsNumber(s, at)) checkInteger(s, at);
  if (next_ == Next::Value && (c == '\'' || c == '"')) {
    next_ = Next::After;
    return quotedEnd(s, at);
  }
  if (next_ == Next::Value && c == '!') return std::min(s.find(' ', at), s.size());  // a tag
  return keyOrPlain(s, at, !flow, begun);
}

/// A key (up to ':'; in block context also any plain value, which the parser reads the same
/// way), or a plain value in a flow collection (up to ',', ']' or '}').
/// `s` is a line of the text yamlShapeProblem() reads: it is followed by '\n' or by the string's
/// terminating NUL, so that strcspn (a library scan: this one runs over most bytes of a file)
/// stops at the line's end at the latest.
std::size_t ShapeScan::keyOrPlain(std::string_view s, std::size_t at, bool key, int& begun) {
  // The bytes that end a key or a plain value: its delimiters, and every control byte.
#define MULTISLIT_CONTROL_BYTES                                                                  \
  "\x01\x02\x03\x04\x05\x06\x07\x08\x09\x0a\x0b\x0c\x0d\x0e\x0f\x10\x11\x12\x13\x14\x15\x16\x17" \
  "\x18\x19\x1a\x1b\x1c\x1d\x1e\x1f"
  static constexpr const char* kKeyEnd = ":" MULTISLIT_CONTROL_BYTES;
  static constexpr const char* kPlainEnd = ",]}" MULTISLIT_CONTROL_BYTES;
#undef MULTISLIT_CONTROL_BYTES
  const std::size_t end =
      std::min(s.size(), at + std::strcspn(s.data() + at, key ? kKeyEnd : kPlainEnd));
  if (key && end < s.size() && s[end] == ':') {
    begun += stack_.empty() ? 1 : 0;  // a block map begun (or an entry of one)
    next_ = Next::Value;
    return end + 1;
  }
  next_ = Next::After;
  return std::max(end, at + 1);
}

void ShapeScan::checkInteger(std::string_view s, std::size_t at) {
  if (!integer_problem_.empty()) return;
  const std::size_t digits_at = at + (s[at] == '-' || s[at] == '+' ? 1 : 0);
  std::size_t end = digits_at;
  while (end < s.size() && digit(s[end])) ++end;
  if (end < s.size() && (s[end] == '.' || s[end] == 'e')) return;  // a real
  const std::string text(s.substr(at, 64));
  errno = 0;
  const long long v = std::strtoll(text.c_str(), nullptr, 0);
  const std::string where = "line " + std::to_string(number_) + " " + quoted(s);
  const std::string shown(s.substr(at, std::max<std::size_t>(end - at, 1)).substr(0, 40));
  if (errno == ERANGE || v < INT_MIN || v > INT_MAX)
    integer_problem_ = where + ": the integer " + shown +
                       " is outside [-2147483648, 2147483647], all a config file may hold";
  else if (end > digits_at + 1 && s[digits_at] == '0')
    integer_problem_ = where + ": the integer " + shown +
                       " begins with 0, which would read it as octal; write it without";
}

std::string ShapeScan::problem() const {
  if (deepest_ > static_cast<std::size_t>(kMaxYamlNesting) || widest_ > kMaxYamlIndent)
    return "nested " +
           (deepest_ > static_cast<std::size_t>(kMaxYamlNesting)
                ? std::to_string(deepest_) + " brackets"
                : std::to_string(widest_) + " spaces") +
           " deep, more than the limit of " + std::to_string(kMaxYamlNesting) + " brackets or " +
           std::to_string(kMaxYamlIndent) + " spaces";
  if (most_begun_ > static_cast<std::size_t>(kMaxYamlNesting))
    return "line " + std::to_string(most_begun_line_) + " begins " + std::to_string(most_begun_) +
           " nested collections (\"- \" or \"key:\"), more than the limit of " +
           std::to_string(kMaxYamlNesting);
  return integer_problem_;
}

/// A file that starts another way than one block map, its keys at the start of a line (a key
/// indented, a list, a flow {...}, "...", a second "---"), or has a document end "..." later:
/// when the first map ends before the file does, the parser looks for a second document, and
/// one starting with '-' (not "---") makes it loop forever; a line starting with ':' (an empty
/// key), on which it reads before its buffer; a NUL, which ends its C strings early.
std::string layoutProblem(const std::string& text) {
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos)
    return "line " + std::to_string(1 + std::count(text.begin(), text.begin() + nul, '\n')) +
           " holds a NUL byte: not a text file";
  constexpr const char* kSpace = " \t\r";
  bool content = false, started = false;
  std::size_t number = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const std::string_view line = std::string_view(text).substr(at, end - at);
    at = end + 1;
    ++number;
    const std::size_t first = line.find_first_not_of(kSpace);
    if (first == std::string_view::npos || line[first] == '#') continue;  // blank or a comment
    const auto where = [number] { return "line " + std::to_string(number); };
    if (line[first] == ':') return where() + " starts with ':' (an empty key)";
    if (!content) {
      const bool dashes = line.compare(0, 3, "---") == 0;
      const std::size_t after = dashes ? line.find_first_not_of(kSpace, 3) : 0;
      const bool document_start = dashes && (after == std::string_view::npos || line[after] == '#');
      if (document_start && started) return where() + " starts a second document (\"---\")";
      started = started || document_start;
      if (line[0] == '%' || document_start) continue;  // a directive (%YAML:1.0), "---"
      content = true;
      const auto c = static_cast<unsigned char>(line[0]);
      if (!std::isalnum(c) && c != '_')
        return where() + " must be the first key of a map, at the start of the line";
    } else if (line.compare(0, 3, "...") == 0) {
      return where() + " ends the document (\"...\"): a file holds one map";
    }
  }
  return "";
}

}  // namespace

std::string yamlShapeProblem(const std::string& text) {
  ShapeScan scan;
  std::size_t number = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    scan.line(std::string_view(text).substr(at, end - at), ++number);
    at = end + 1;
  }
  const std::string problem = scan.problem();
  return problem.empty() ? layoutProblem(text) : problem;
}

}  // namespace multislit
