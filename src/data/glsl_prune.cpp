#include "data/glsl_prune.hpp"

#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace atmos::data {

namespace {

bool identifier_start(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool identifier_char(char c) { return identifier_start(c) || (c >= '0' && c <= '9'); }
bool digit(char c) { return c >= '0' && c <= '9'; }
bool blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// A token of the code outside directives and comments.
struct Token {
  enum Kind { identifier, number, punctuation, directive } kind;
  size_t begin = 0;  // offsets in the source
  size_t end = 0;
  // Directives: 1 opens a conditional (#if, #ifdef, #ifndef), 2 continues
  // it (#elif, #else), 3 closes it (#endif), 0 any other.
  int conditional = 0;
};

// The source as tokens, the identifiers of its directives (names, #if
// conditions, macro bodies) and the names of its macros; nullopt where the
// text is beyond the parse (see the header).
struct Lexed {
  std::vector<Token> tokens;
  std::vector<std::string_view> directive_identifiers;
  std::unordered_set<std::string_view> macros;
};

// Lexes the directive starting at the '#' at `i`; returns the offset of the
// newline that ends it (or the end of the source), npos if unsupported.
size_t lex_directive(std::string_view s, size_t i, Lexed& out) {
  const size_t begin = i;
  ++i;  // '#'
  std::vector<std::string_view> names;
  int parens = 0;
  bool body_has_hash = false, body_has_block = false;
  while (i < s.size()) {
    const char c = s[i];
    if (c == '\\' && i + 1 < s.size() && (s[i + 1] == '\n' || (s[i + 1] == '\r' && i + 2 < s.size() && s[i + 2] == '\n'))) {
      i += s[i + 1] == '\n' ? 2 : 3;
    } else if (c == '\n') {
      break;
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '/') {
      while (i < s.size() && s[i] != '\n') {
        if (s[i] == '\\' && i + 1 < s.size() && (s[i + 1] == '\n' || s[i + 1] == '\r')) return std::string_view::npos;
        ++i;
      }
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '*') {
      const size_t close = s.find("*/", i + 2);
      if (close == std::string_view::npos) return std::string_view::npos;
      i = close + 2;
    } else if (identifier_start(c)) {
      const size_t start = i;
      while (i < s.size() && identifier_char(s[i])) ++i;
      names.push_back(s.substr(start, i - start));
    } else if (digit(c)) {
      while (i < s.size() && (identifier_char(s[i]) || s[i] == '.')) ++i;
    } else {
      if (!names.empty()) {
        if (c == '#') body_has_hash = true;
        if (c == '{' || c == '}' || c == ';') body_has_block = true;
        if (c == '(') ++parens;
        if (c == ')') --parens;
      }
      ++i;
    }
  }
  if (names.empty()) return i;  // the null directive "#"
  const std::string_view name = names[0];
  Token t{Token::directive, begin, i, 0};
  if (name == "if" || name == "ifdef" || name == "ifndef") t.conditional = 1;
  else if (name == "elif" || name == "else") t.conditional = 2;
  else if (name == "endif") t.conditional = 3;
  if (name == "define") {
    if (names.size() < 2) return std::string_view::npos;
    // A body that pastes or stringizes tokens, or holds braces, semicolons or
    // unbalanced parentheses, could make or hide definitions the parse does
    // not see. (The parameter list's parentheses are balanced.)
    if (body_has_hash || body_has_block || parens != 0) return std::string_view::npos;
    out.macros.insert(names[1]);
  }
  for (size_t k = 1; k < names.size(); ++k) out.directive_identifiers.push_back(names[k]);
  out.tokens.push_back(t);
  return i;
}

std::optional<Lexed> lex(std::string_view s) {
  Lexed out;
  bool line_start = true;  // only blanks and comments since the last newline
  size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    if (c == '\n') {
      line_start = true;
      ++i;
    } else if (blank(c)) {
      ++i;
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '/') {
      while (i < s.size() && s[i] != '\n') {
        // A continued line comment would swallow the next line.
        if (s[i] == '\\' && i + 1 < s.size() && (s[i + 1] == '\n' || s[i + 1] == '\r')) return std::nullopt;
        ++i;
      }
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '*') {
      const size_t close = s.find("*/", i + 2);
      if (close == std::string_view::npos) return std::nullopt;
      if (s.substr(i, close - i).find('\n') != std::string_view::npos) line_start = true;
      i = close + 2;
    } else if (c == '#') {
      if (!line_start) return std::nullopt;
      i = lex_directive(s, i, out);
      if (i == std::string_view::npos) return std::nullopt;
    } else if (identifier_start(c)) {
      const size_t begin = i;
      while (i < s.size() && identifier_char(s[i])) ++i;
      out.tokens.push_back({Token::identifier, begin, i, 0});
      line_start = false;
    } else if (digit(c) || (c == '.' && i + 1 < s.size() && digit(s[i + 1]))) {
      // A preprocessing number: 1.0f, 6.4e-3, 0x1Fu.
      const size_t begin = i;
      while (i < s.size()) {
        if ((s[i] == 'e' || s[i] == 'E') && i + 1 < s.size() && (s[i + 1] == '+' || s[i + 1] == '-')) i += 2;
        else if (identifier_char(s[i]) || s[i] == '.') ++i;
        else break;
      }
      out.tokens.push_back({Token::number, begin, i, 0});
      line_start = false;
    } else if (c == '\\') {
      return std::nullopt;  // line continuation in code
    } else {
      out.tokens.push_back({Token::punctuation, i, i + 1, 0});
      line_start = false;
      ++i;
    }
  }
  return out;
}

// A top-level function definition: tokens [first, last] (the return type to
// the closing brace) and its name.
struct Definition {
  size_t first = 0, last = 0;
  std::string_view name;
  bool removable = false;  // outside #if regions, without directives
};

// The top-level function definitions of the tokens; nullopt if braces or
// parentheses do not balance, overall or within a branch of an #if.
std::optional<std::vector<Definition>> definitions(std::string_view s, const std::vector<Token>& tokens) {
  constexpr size_t none = size_t(-1);
  std::vector<Definition> found;
  struct Frame {
    int braces, parens;
  };
  std::vector<Frame> conditionals;
  std::vector<size_t> open_parens;
  int braces = 0;
  size_t statement = none;              // first token of the current top-level statement
  bool statement_has_directive = false;
  bool statement_has_block = false;     // a brace pair before this point (a struct, a macro's header)
  size_t statement_conditionals = 0;    // #if depth at its start
  size_t last_code = none;              // last token that is not a directive
  size_t last_close_opener = none;      // the '(' matching the last ')'
  std::optional<Definition> current;    // the definition whose body is open
  const auto is = [&](size_t k, char c) {
    return tokens[k].kind == Token::punctuation && s[tokens[k].begin] == c;
  };
  for (size_t k = 0; k < tokens.size(); ++k) {
    const Token& t = tokens[k];
    if (t.kind == Token::directive) {
      statement_has_directive = true;
      const Frame here{braces, int(open_parens.size())};
      if (t.conditional == 1) {
        conditionals.push_back(here);
      } else if (t.conditional >= 2) {
        if (conditionals.empty()) return std::nullopt;
        if (conditionals.back().braces != here.braces || conditionals.back().parens != here.parens)
          return std::nullopt;
        if (t.conditional == 3) conditionals.pop_back();
      }
      continue;
    }
    if (braces == 0 && statement == none) {
      statement = k;
      statement_has_directive = false;
      statement_has_block = false;
      statement_conditionals = conditionals.size();
    }
    if (is(k, '(')) {
      open_parens.push_back(k);
    } else if (is(k, ')')) {
      if (open_parens.empty()) return std::nullopt;
      last_close_opener = open_parens.back();
      open_parens.pop_back();
    } else if (is(k, '{')) {
      if (braces == 0 && open_parens.empty() && last_code != none && is(last_code, ')')) {
        // "<type> <name>(<parameters>) {": a function definition (the
        // parameters' '(' follows the name, which follows the return type).
        const size_t opener = last_close_opener;
        if (opener != none && opener > statement + 1 && tokens[opener - 1].kind == Token::identifier) {
          Definition d;
          d.first = statement;
          d.name = s.substr(tokens[opener - 1].begin, tokens[opener - 1].end - tokens[opener - 1].begin);
          d.removable = !statement_has_block;
          current = d;
        }
      }
      if (braces == 0 && !current) statement_has_block = true;
      ++braces;
    } else if (is(k, '}')) {
      if (--braces < 0) return std::nullopt;
      if (braces == 0 && current) {
        current->last = k;
        current->removable = current->removable && statement_conditionals == 0 && !statement_has_directive;
        found.push_back(*current);
        current.reset();
        statement = none;
      }
    } else if (is(k, ';') && braces == 0 && open_parens.empty()) {
      statement = none;
    }
    last_code = k;
  }
  if (braces != 0 || !open_parens.empty() || !conditionals.empty()) return std::nullopt;
  return found;
}

}  // namespace

std::string prune_unreferenced_functions(std::string_view source) {
  const std::optional<Lexed> lexed = lex(source);
  if (!lexed) return std::string(source);
  const std::vector<Token>& tokens = lexed->tokens;
  std::optional<std::vector<Definition>> found = definitions(source, tokens);
  if (!found) return std::string(source);
  std::vector<Definition>& defs = *found;
  const auto text = [&](const Token& t) { return source.substr(t.begin, t.end - t.begin); };

  // A definition whose name is a macro is one the macro spells: kept.
  for (Definition& d : defs)
    if (d.name == "main" || lexed->macros.count(d.name) > 0) d.removable = false;

  // The candidates by name; a name with a definition that must stay keeps
  // its overloads (the fixpoint below reaches them through that body too).
  std::unordered_map<std::string_view, std::vector<size_t>> by_name;
  for (size_t i = 0; i < defs.size(); ++i)
    if (defs[i].removable) by_name[defs[i].name].push_back(i);
  if (by_name.empty()) return std::string(source);

  // Identifiers of kept text: directives, tokens outside candidates, and
  // the names of definitions that stay.
  std::unordered_set<std::string_view> reached;
  std::vector<std::string_view> pending;
  const auto reach = [&](std::string_view name) {
    if (by_name.count(name) > 0 && reached.insert(name).second) pending.push_back(name);
  };
  for (std::string_view name : lexed->directive_identifiers) reach(name);
  for (const Definition& d : defs)
    if (!d.removable) reach(d.name);
  {
    size_t next = 0;  // the next candidate in token order
    std::vector<size_t> order;
    for (size_t i = 0; i < defs.size(); ++i)
      if (defs[i].removable) order.push_back(i);
    for (size_t k = 0; k < tokens.size(); ++k) {
      if (next < order.size() && k == defs[order[next]].first) {
        k = defs[order[next]].last;
        ++next;
        continue;
      }
      if (tokens[k].kind == Token::identifier) reach(text(tokens[k]));
    }
  }
  std::vector<bool> kept(defs.size(), false);
  while (!pending.empty()) {
    const std::string_view name = pending.back();
    pending.pop_back();
    for (size_t i : by_name[name]) {
      kept[i] = true;
      for (size_t k = defs[i].first; k <= defs[i].last; ++k)
        if (tokens[k].kind == Token::identifier) reach(text(tokens[k]));
    }
  }

  std::string out;
  out.reserve(source.size());
  size_t copied = 0;
  for (size_t i = 0; i < defs.size(); ++i) {
    if (!defs[i].removable || kept[i]) continue;
    const size_t begin = tokens[defs[i].first].begin, end = tokens[defs[i].last].end;
    out.append(source.substr(copied, begin - copied));
    for (size_t p = begin; p < end; ++p)
      if (source[p] == '\n') out += '\n';
    copied = end;
  }
  out.append(source.substr(copied));
  return out;
}

}  // namespace atmos::data
