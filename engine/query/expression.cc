#include "engine/query/expression.h"

#include <re2/re2.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <string_view>

#include "engine/common/errors.h"
#include "engine/common/request_error.h"

namespace gesweep {

struct RowFilter::Node {
  enum class Kind {
    kColumn,
    kNumber,
    kString,
    kNot,
    kAnd,
    kOr,
    kCompare,
    kArithmetic,
    kNegate,
    kFunction,
    kTruth,
    kIn,
    kMatch
  };
  /// kBool: 0/1 values; kText: a text column; kString: a string literal.
  enum class Type { kNumber, kBool, kText, kString };
  Kind kind = Kind::kNumber;
  Type type = Type::kNumber;
  int position = 1;   // 1-based column in the expression
  int column = -1;    // kColumn
  double number = 0;  // kNumber
  int height = 1;     // levels of nodes from here down (a leaf is 1)
  // kString: the literal; kCompare/kArithmetic: the operator; kFunction: its name;
  // kMatch: "contains" (text is then the substring) or the pattern of "matches".
  std::string text;
  bool negated = false;                   // kIn, kMatch: "not in", "not contains", "not matches"
  std::vector<double> numbers;            // kIn: the listed numbers (level codes), sorted, no NaN
  std::vector<std::string> strings;       // kIn on a text column: the listed strings, sorted
  std::shared_ptr<const re2::RE2> regex;  // kMatch with "matches"
  std::unique_ptr<Node> left, right;
};

namespace {

using Node = RowFilter::Node;
using Kind = Node::Kind;
using Type = Node::Type;

enum class TokenKind { kNumber, kString, kName, kOperator, kEnd };

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string text;
  double number = 0;
  int position = 1;
};

bool NameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool NameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }

// Nesting of parentheses, function calls, `not` and unary minus: each level is a few stack frames
// of this recursive-descent parser, so a limit keeps any expression far from the stack's end (the
// CLI's 8 MB, a sanitizer's larger frames). No condition a person writes nests this deep.
constexpr int kMaxNesting = 256;
// Height of the parsed tree, which also grows along a chain (a + b + c ..., a or b or c ...):
// evaluating and destroying the tree recurse along it. `in (...)` writes long lists of
// alternatives as one node.
constexpr int kMaxHeight = 1024;
// An expression longer than this is echoed in an error message by its start and its length only.
constexpr std::size_t kEchoedLength = 80;

bool IsKeyword(const std::string& name) {
  static const char* const kKeywords[] = {"and", "or",    "not",      "true", "false",    "inf",    "nan",
                                          "abs", "isnan", "isfinite", "in",   "contains", "matches"};
  return std::any_of(std::begin(kKeywords), std::end(kKeywords), [&](const char* k) { return name == k; });
}

class Parser {
 public:
  Parser(const std::string& text, const ColumnCatalog& catalog, const std::string& flag)
      : text_(text), catalog_(catalog), flag_(flag) {
    Lex();
  }

  std::unique_ptr<Node> ParseCondition() {
    if (tokens_.size() == 1) Fail(1, "empty expression; expected a condition such as height_m < 3");
    auto node = ParseOr();
    if (Peek().kind != TokenKind::kEnd) {
      if (Peek().kind == TokenKind::kOperator && Peek().text == ")") Fail(Peek().position, "unmatched ')'");
      Fail(Peek().position, "expected and, or, or the end of the expression, found '" + Peek().text + "'");
    }
    return AsCondition(std::move(node));
  }

  std::vector<int> columns() const {
    std::vector<int> sorted = columns_;
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    return sorted;
  }

 private:
  [[noreturn]] void Fail(int position, const std::string& what, const std::string& remedy = "") const {
    const std::string shown =
        text_.size() <= kEchoedLength
            ? "'" + text_ + "'"
            : "'" + text_.substr(0, kEchoedLength) + "...' (" + std::to_string(text_.size()) + " characters)";
    throw RequestError("command line", flag_, shown, "at column " + std::to_string(position) + ": " + what,
                       remedy);
  }

  // One more level of nesting for as long as it lives; refuses the level past kMaxNesting.
  class Nest {
   public:
    Nest(Parser& parser, int position) : parser_(parser) {
      if (++parser_.depth_ > kMaxNesting) {
        parser_.Fail(position, "nested deeper than " + std::to_string(kMaxNesting) +
                                   " levels (parentheses, function calls, not, unary minus); "
                                   "write a flatter expression");
      }
    }
    ~Nest() { --parser_.depth_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;

   private:
    Parser& parser_;
  };

  // Sets the height of a node whose children are in place; refuses a tree past kMaxHeight.
  std::unique_ptr<Node> Grown(std::unique_ptr<Node> node) const {
    int below = 0;
    if (node->left) below = std::max(below, node->left->height);
    if (node->right) below = std::max(below, node->right->height);
    node->height = below + 1;
    if (node->height > kMaxHeight) {
      Fail(node->position, "more than " + std::to_string(kMaxHeight) +
                               " levels of operators (a very long chain of and, or, +, ...); "
                               "split the condition, or write a list of alternatives as x in (a, b, c)");
    }
    return node;
  }

  // A number at text_[i] into `token`; the index past it.
  std::size_t LexNumber(std::size_t i, Token& token) {
    const std::size_t n = text_.size();
    const int position = token.position;
    const char* begin = text_.c_str() + i;
    char* end = nullptr;
    token.number = std::strtod(begin, &end);
    const std::size_t length = static_cast<std::size_t>(end - begin);
    if (length == 0) Fail(position, "malformed number");
    i += length;
    if (i < n && NameStart(text_[i]))
      Fail(position, "malformed number '" + text_.substr(position - 1, i - position + 2) + "'");
    token.kind = TokenKind::kNumber;
    token.text = text_.substr(static_cast<std::size_t>(position - 1), length);
    return i;
  }

  // A name at text_[i]: letters, digits, '_', '.', and '/' followed by a name character (dataset
  // paths); the index past it.
  std::size_t LexName(std::size_t i, Token& token) {
    const std::size_t n = text_.size();
    std::size_t j = i;
    while (j < n && (NameChar(text_[j]) || (text_[j] == '/' && j + 1 < n && NameStart(text_[j + 1])))) ++j;
    std::string name = text_.substr(i, j - i);
    // "a/b" is one column when it names one; else the longest prefix that does, then "/".
    if (!IsKeyword(name) && !catalog_.Find(name)) {
      for (std::size_t cut = name.rfind('/'); cut != std::string::npos && cut > 0;
           cut = name.rfind('/', cut - 1)) {
        if (catalog_.Find(name.substr(0, cut))) {
          name = name.substr(0, cut);
          break;
        }
      }
    }
    token.kind = TokenKind::kName;
    token.text = name;
    return i + name.size();
  }

  // An operator at text_[i] (or the one line on a character that is none); the index past it.
  std::size_t LexOperator(std::size_t i, Token& token) {
    const char c = text_[i];
    const int position = token.position;
    static const char* const kOperators[] = {"==", "!=", "<=", ">=", "<", ">", "+",
                                             "-",  "*",  "/",  "%",  "(", ")", ","};
    token.kind = TokenKind::kOperator;
    for (const char* op : kOperators) {
      const std::size_t length = std::char_traits<char>::length(op);
      if (text_.compare(i, length, op) == 0) {
        token.text = op;
        break;
      }
    }
    if (token.text.empty()) {
      if (c == '=') Fail(position, "'=' is not an operator; write '==' to compare");
      if (c == '&' || c == '|') Fail(position, "write 'and' / 'or' instead of '" + std::string(1, c) + "'");
      if (c == '!') Fail(position, "write 'not' instead of '!'");
      Fail(position, "unexpected character '" + std::string(1, c) + "'");
    }
    return i + token.text.size();
  }

  void Lex() {
    std::size_t i = 0;
    const std::size_t n = text_.size();
    // A "/" where an operand is expected starts a full dataset path ("/design/height_m"); after an
    // operand it divides.
    bool operand_expected = true;
    while (i < n) {
      const char c = text_[i];
      const int position = static_cast<int>(i) + 1;
      if (std::isspace(static_cast<unsigned char>(c))) {
        ++i;
        continue;
      }
      Token token;
      token.position = position;
      if (std::isdigit(static_cast<unsigned char>(c)) ||
          (c == '.' && i + 1 < n && std::isdigit(static_cast<unsigned char>(text_[i + 1])))) {
        i = LexNumber(i, token);
      } else if (c == '"' || c == '\'') {
        const std::size_t close = text_.find(c, i + 1);
        if (close == std::string::npos)
          Fail(position, "unterminated string (no closing " + std::string(1, c) + ")");
        token.kind = TokenKind::kString;
        token.text = text_.substr(i + 1, close - i - 1);
        i = close + 1;
      } else if (NameStart(c) || (c == '/' && operand_expected && i + 1 < n && NameStart(text_[i + 1]))) {
        i = LexName(i, token);
      } else {
        i = LexOperator(i, token);
      }
      operand_expected = token.kind == TokenKind::kOperator
                             ? token.text != ")"
                             : token.kind == TokenKind::kName && IsKeyword(token.text) &&
                                   token.text != "true" && token.text != "false" && token.text != "inf" &&
                                   token.text != "nan";
      tokens_.push_back(std::move(token));
    }
    Token end;
    end.position = static_cast<int>(n) + 1;
    end.text = "end of expression";
    tokens_.push_back(end);
  }

  const Token& Peek() const { return tokens_[next_]; }
  // The next token; the end token is never passed.
  const Token& Take() {
    const Token& token = tokens_[next_];
    if (token.kind != TokenKind::kEnd) ++next_;
    return token;
  }
  bool TakeName(const char* keyword) {
    if (Peek().kind == TokenKind::kName && Peek().text == keyword) {
      ++next_;
      return true;
    }
    return false;
  }
  bool TakeOperator(const char* op) {
    if (Peek().kind == TokenKind::kOperator && Peek().text == op) {
      ++next_;
      return true;
    }
    return false;
  }

  static std::unique_ptr<Node> Make(Kind kind, Type type, int position) {
    auto node = std::make_unique<Node>();
    node->kind = kind;
    node->type = type;
    node->position = position;
    return node;
  }

  std::string Describe(const Node& node) const {
    if (node.kind == Kind::kColumn) return catalog_.column(node.column).name;
    if (node.kind == Kind::kString) return "\"" + node.text + "\"";
    return "the expression at column " + std::to_string(node.position);
  }

  // A boolean-valued node, or a false/true column standing alone.
  std::unique_ptr<Node> AsCondition(std::unique_ptr<Node> node) {
    if (node->type == Type::kBool) return node;
    if (node->kind == Kind::kColumn && catalog_.column(node->column).boolean()) {
      auto truth = Make(Kind::kTruth, Type::kBool, node->position);
      truth->left = std::move(node);
      return Grown(std::move(truth));
    }
    Fail(node->position, "expected a condition (a comparison such as x < 1, or a false/true column), found " +
                             Describe(*node));
  }

  // operand (word operand)*, grouped from the left: `or` over `and` terms, `and` over `not` terms.
  std::unique_ptr<Node> ParseConnective(const char* word, Kind kind,
                                        std::unique_ptr<Node> (Parser::*operand)()) {
    auto left = (this->*operand)();
    while (Peek().kind == TokenKind::kName && Peek().text == word) {
      const int position = Take().position;
      auto node = Make(kind, Type::kBool, position);
      node->left = AsCondition(std::move(left));
      node->right = AsCondition((this->*operand)());
      left = Grown(std::move(node));
    }
    return left;
  }

  std::unique_ptr<Node> ParseOr() { return ParseConnective("or", Kind::kOr, &Parser::ParseAnd); }
  std::unique_ptr<Node> ParseAnd() { return ParseConnective("and", Kind::kAnd, &Parser::ParseNot); }

  std::unique_ptr<Node> ParseNot() {
    if (Peek().kind == TokenKind::kName && Peek().text == "not") {
      const int position = Take().position;
      const Nest nest(*this, position);
      auto node = Make(Kind::kNot, Type::kBool, position);
      node->left = AsCondition(ParseNot());
      return Grown(std::move(node));
    }
    return ParseComparison();
  }

  static bool IsComparison(const Token& token) {
    if (token.kind != TokenKind::kOperator) return false;
    return token.text == "==" || token.text == "!=" || token.text == "<" || token.text == "<=" ||
           token.text == ">" || token.text == ">=";
  }

  // The level index of `literal` in `column`, or a refusal naming the levels.
  double LevelIndex(const std::string& literal, int position, const RunColumn& column) const {
    const auto it = std::find(column.levels.begin(), column.levels.end(), literal);
    if (it == column.levels.end()) {
      std::string levels;
      for (const auto& level : column.levels) levels += (levels.empty() ? "" : ", ") + level;
      Fail(position,
           "\"" + literal + "\" is not a level of " + column.name + " (expected one of " + levels + ")");
    }
    return static_cast<double>(it - column.levels.begin());
  }

  // A string literal compared with a column that has levels becomes the level's index.
  void CoerceLevel(std::unique_ptr<Node>& literal, const Node& column_node) {
    auto number = Make(Kind::kNumber, Type::kNumber, literal->position);
    number->number = LevelIndex(literal->text, literal->position, catalog_.column(column_node.column));
    literal = std::move(number);
  }

  bool IsLevelColumn(const Node& node) const {
    return node.kind == Kind::kColumn && !catalog_.column(node.column).levels.empty();
  }

  // After an operand: "in", "contains", "matches", or "not" followed by one of them.
  bool AtMembership() const {
    auto is_word = [](const Token& t) {
      return t.kind == TokenKind::kName && (t.text == "in" || t.text == "contains" || t.text == "matches");
    };
    if (is_word(Peek())) return true;
    return Peek().kind == TokenKind::kName && Peek().text == "not" && next_ + 1 < tokens_.size() &&
           is_word(tokens_[next_ + 1]);
  }

  std::unique_ptr<Node> ParseComparison() {
    auto left = ParseSum();
    if (AtMembership()) return ParseMembership(std::move(left));
    if (!IsComparison(Peek())) return left;
    const Token op = Take();
    auto right = ParseSum();
    if (IsComparison(Peek())) {
      Fail(Peek().position, "comparisons do not chain; write a < b and b < c");
    }
    if (left->type == Type::kBool || right->type == Type::kBool) {
      const Node& bad = left->type == Type::kBool ? *left : *right;
      Fail(bad.position, "a condition cannot be compared; use and, or, not");
    }
    if (left->type == Type::kString && right->type == Type::kString) {
      Fail(op.position, "both sides are strings; compare a column with a string");
    }
    if (left->type == Type::kString || right->type == Type::kString) {
      std::unique_ptr<Node>& literal = left->type == Type::kString ? left : right;
      const Node& other = left->type == Type::kString ? *right : *left;
      if (other.type == Type::kText) {
        // text == "..." compares strings.
      } else if (IsLevelColumn(other)) {
        CoerceLevel(literal, other);
      } else {
        Fail(literal->position, "\"" + literal->text + "\" is a string but " + Describe(other) +
                                    " is a number (strings compare with message or a column with levels, "
                                    "e.g. status == \"failed\")");
      }
    } else if ((left->type == Type::kText) != (right->type == Type::kText)) {
      const Node& text = left->type == Type::kText ? *left : *right;
      Fail(text.position, catalog_.column(text.column).name + " is text; compare it with a string");
    }
    auto node = Make(Kind::kCompare, Type::kBool, op.position);
    node->text = op.text;
    node->left = std::move(left);
    node->right = std::move(right);
    return Grown(std::move(node));
  }

  // One item of an `in` list: a number (optionally signed), true, false, inf, nan, or a string.
  // Returns true for a string (in `*text`), false for a number (in `*number`).
  bool ParseListItem(double* number, std::string* text, int* position) {
    const Token token = Take();
    *position = token.position;
    if (token.kind == TokenKind::kString) {
      *text = token.text;
      return true;
    }
    double sign = 1.0;
    Token value = token;
    if (token.kind == TokenKind::kOperator && (token.text == "-" || token.text == "+")) {
      sign = token.text == "-" ? -1.0 : 1.0;
      value = Take();
    }
    if (value.kind == TokenKind::kNumber) {
      *number = sign * value.number;
      return false;
    }
    if (value.kind == TokenKind::kName &&
        (value.text == "true" || value.text == "false" || value.text == "inf" || value.text == "nan")) {
      *number = sign * (value.text == "true"    ? 1.0
                        : value.text == "false" ? 0.0
                        : value.text == "inf"   ? std::numeric_limits<double>::infinity()
                                                : std::nan(""));
      return false;
    }
    Fail(value.position, "an in (...) list holds numbers or \"strings\", found '" + value.text +
                             "' (to compare with a column, write x == a or x == b)");
  }

  // x [not] in (a, b, ...), x [not] contains "text", x [not] matches "regex".
  std::unique_ptr<Node> ParseMembership(std::unique_ptr<Node> left) {
    const bool negated = TakeName("not");
    const Token word = Take();
    if (left->type == Type::kBool) Fail(left->position, "a condition cannot be compared; use and, or, not");
    if (left->type == Type::kString) {
      Fail(left->position,
           "\"" + left->text + "\" is a string; write the column on the left of " + word.text);
    }
    const bool text_column = left->type == Type::kText;
    const bool level_column = IsLevelColumn(*left);
    auto node = Make(Kind::kIn, Type::kBool, word.position);
    node->negated = negated;
    if (word.text == "in") {
      if (!TakeOperator("(")) Fail(Peek().position, "expected '(' after in, e.g. speed_mps in (30, 32.0208)");
      do {
        double number = 0;
        std::string text;
        int position = 0;
        if (ParseListItem(&number, &text, &position)) {
          if (level_column) {
            node->numbers.push_back(LevelIndex(text, position, catalog_.column(left->column)));
          } else if (text_column) {
            node->strings.push_back(text);
          } else {
            Fail(position, "\"" + text + "\" is a string but " + Describe(*left) +
                               " is a number (strings are levels of a column with levels, or text)");
          }
        } else {
          if (text_column) Fail(position, Describe(*left) + " is text; list strings, e.g. (\"a\", \"b\")");
          if (!std::isnan(number)) node->numbers.push_back(number);  // NaN equals nothing
        }
      } while (TakeOperator(","));
      if (!TakeOperator(")")) Fail(Peek().position, "expected ',' or ')' in the in (...) list");
      std::sort(node->numbers.begin(), node->numbers.end());
      node->numbers.erase(std::unique(node->numbers.begin(), node->numbers.end()), node->numbers.end());
      std::sort(node->strings.begin(), node->strings.end());
      node->strings.erase(std::unique(node->strings.begin(), node->strings.end()), node->strings.end());
      node->left = std::move(left);
      return Grown(std::move(node));
    }
    // contains / matches: a text column, or a column with levels (then: the levels that match).
    if (Peek().kind != TokenKind::kString) {
      Fail(Peek().position, "expected a \"string\" after " + word.text);
    }
    const Token pattern = Take();
    if (!text_column && !level_column) {
      Fail(left->position, Describe(*left) + " is a number; " + word.text +
                               " applies to message or a column with levels (status, end_event, ...)");
    }
    std::shared_ptr<const re2::RE2> regex;
    if (word.text == "matches") {
      re2::RE2::Options options;
      options.set_log_errors(false);  // the error comes back as data, never printed here
      auto compiled = std::make_shared<const re2::RE2>(pattern.text, options);
      if (!compiled->ok())
        Fail(pattern.position, "not a regular expression (RE2 syntax): " + compiled->error());
      regex = std::move(compiled);
    }
    if (level_column) {
      const RunColumn& column = catalog_.column(left->column);
      for (std::size_t level = 0; level < column.levels.size(); ++level) {
        const std::string& name = column.levels[level];
        const bool hit =
            regex ? re2::RE2::PartialMatch(name, *regex) : name.find(pattern.text) != std::string::npos;
        if (hit) node->numbers.push_back(static_cast<double>(level));
      }
      node->left = std::move(left);
      return Grown(std::move(node));
    }
    node->kind = Kind::kMatch;
    node->text = pattern.text;
    node->regex = std::move(regex);
    node->left = std::move(left);
    return Grown(std::move(node));
  }

  void RequireNumber(const Node& node) const {
    if (node.type == Type::kNumber) return;
    if (node.type == Type::kBool) Fail(node.position, "a condition is not a number");
    Fail(node.position, Describe(node) + " is text, not a number");
  }

  // operand (op operand)*, grouped from the left, for the operators `ops`: sums of products,
  // products of unary terms.
  std::unique_ptr<Node> ParseArithmetic(std::initializer_list<std::string_view> ops,
                                        std::unique_ptr<Node> (Parser::*operand)()) {
    auto left = (this->*operand)();
    while (Peek().kind == TokenKind::kOperator &&
           std::find(ops.begin(), ops.end(), Peek().text) != ops.end()) {
      const Token op = Take();
      auto node = Make(Kind::kArithmetic, Type::kNumber, op.position);
      node->text = op.text;
      RequireNumber(*left);
      node->left = std::move(left);
      node->right = (this->*operand)();
      RequireNumber(*node->right);
      left = Grown(std::move(node));
    }
    return left;
  }

  std::unique_ptr<Node> ParseSum() { return ParseArithmetic({"+", "-"}, &Parser::ParseProduct); }
  std::unique_ptr<Node> ParseProduct() { return ParseArithmetic({"*", "/", "%"}, &Parser::ParseUnary); }

  std::unique_ptr<Node> ParseUnary() {
    if (Peek().kind == TokenKind::kOperator && Peek().text == "-") {
      const int position = Take().position;
      const Nest nest(*this, position);
      auto node = Make(Kind::kNegate, Type::kNumber, position);
      node->left = ParseUnary();
      RequireNumber(*node->left);
      return Grown(std::move(node));
    }
    return ParsePrimary();
  }

  std::unique_ptr<Node> ParsePrimary() {
    const Token token = Take();
    switch (token.kind) {
      case TokenKind::kNumber: {
        auto node = Make(Kind::kNumber, Type::kNumber, token.position);
        node->number = token.number;
        return node;
      }
      case TokenKind::kString: {
        auto node = Make(Kind::kString, Type::kString, token.position);
        node->text = token.text;
        return node;
      }
      case TokenKind::kOperator:
        if (token.text == "(") {
          const Nest nest(*this, token.position);
          auto inner = ParseOr();
          if (!TakeOperator(")"))
            Fail(Peek().position,
                 "expected ')' to close the '(' at column " + std::to_string(token.position));
          return inner;
        }
        Fail(token.position, "expected a column, a number or '(', found '" + token.text + "'");
      case TokenKind::kEnd:
        Fail(token.position, "the expression ends too early; expected a column, a number or '('");
      case TokenKind::kName:
        break;
    }
    const std::string& name = token.text;
    if (name == "true" || name == "false" || name == "inf" || name == "nan") {
      auto node = Make(Kind::kNumber, Type::kNumber, token.position);
      node->number = name == "true"    ? 1.0
                     : name == "false" ? 0.0
                     : name == "inf"   ? std::numeric_limits<double>::infinity()
                                       : std::nan("");
      return node;
    }
    if (name == "abs" || name == "isnan" || name == "isfinite") {
      if (!TakeOperator("(")) Fail(Peek().position, "expected '(' after " + name);
      const Nest nest(*this, token.position);
      auto node = Make(Kind::kFunction, name == "abs" ? Type::kNumber : Type::kBool, token.position);
      node->text = name;
      node->left = ParseSum();
      RequireNumber(*node->left);
      if (!TakeOperator(")")) Fail(Peek().position, "expected ')' to close " + name + "(");
      return Grown(std::move(node));
    }
    if (name == "and" || name == "or" || name == "not") {
      Fail(token.position, "'" + name + "' needs a condition before/after it");
    }
    if (name == "in" || name == "contains" || name == "matches") {
      Fail(token.position, "'" + name + "' needs a column before it, e.g. status in (\"ok\", \"failed\")");
    }
    std::string problem, remedy;
    const auto column = catalog_.Resolve(name, &problem, &remedy);
    if (!column) Fail(token.position, problem, remedy);
    auto node =
        Make(Kind::kColumn, catalog_.column(*column).kind == ColumnKind::kText ? Type::kText : Type::kNumber,
             token.position);
    node->column = *column;
    columns_.push_back(*column);
    return node;
  }

  const std::string& text_;
  const ColumnCatalog& catalog_;
  const std::string& flag_;
  std::vector<Token> tokens_;
  std::size_t next_ = 0;
  int depth_ = 0;
  std::vector<int> columns_;
};

// a % b with the sign of b, as Python's and NumPy's (numpy.remainder); NaN when b is 0.
double FlooredRemainder(double a, double b) {
  double r = std::fmod(a, b);
  if (r != 0.0 && ((b < 0.0) != (r < 0.0))) r += b;
  return r;
}

bool Compare(const std::string& op, double a, double b) {
  if (op == "==") return a == b;
  if (op == "!=") return a != b;
  if (op == "<") return a < b;
  if (op == "<=") return a <= b;
  if (op == ">") return a > b;
  return a >= b;
}

bool CompareText(const std::string& op, const std::string& a, const std::string& b) {
  const int c = a.compare(b);
  if (op == "==") return c == 0;
  if (op == "!=") return c != 0;
  if (op == "<") return c < 0;
  if (op == "<=") return c <= 0;
  if (op == ">") return c > 0;
  return c >= 0;
}

std::vector<double> Evaluate(const Node& node, const std::vector<ColumnValues>& values, std::size_t n);

// A comparison, of two numbers or of a text column with a text (quoted or another column).
std::vector<double> EvaluateCompare(const Node& node, const std::vector<ColumnValues>& values,
                                    std::size_t n) {
  std::vector<double> out(n);
  if (node.left->type == Type::kText || node.right->type == Type::kText) {
    const bool left_text = node.left->type == Type::kText;
    const Node& column = left_text ? *node.left : *node.right;
    const Node& other = left_text ? *node.right : *node.left;
    const std::vector<std::string>& texts = values[static_cast<std::size_t>(column.column)].texts;
    const std::vector<std::string>* other_texts =
        other.kind == Kind::kColumn ? &values[static_cast<std::size_t>(other.column)].texts : nullptr;
    for (std::size_t i = 0; i < n; ++i) {
      const std::string& b = other_texts ? (*other_texts)[i] : other.text;
      out[i] = left_text ? CompareText(node.text, texts[i], b) : CompareText(node.text, b, texts[i]);
    }
    return out;
  }
  const std::vector<double> a = Evaluate(*node.left, values, n);
  const std::vector<double> b = Evaluate(*node.right, values, n);
  for (std::size_t i = 0; i < n; ++i) out[i] = Compare(node.text, a[i], b[i]) ? 1.0 : 0.0;
  return out;
}

// `in` / `not in` a list of numbers or texts.
std::vector<double> EvaluateIn(const Node& node, const std::vector<ColumnValues>& values, std::size_t n) {
  std::vector<double> out(n);
  if (node.left->type == Type::kText) {
    const std::vector<std::string>& texts = values[static_cast<std::size_t>(node.left->column)].texts;
    for (std::size_t i = 0; i < n; ++i) {
      const bool hit = std::binary_search(node.strings.begin(), node.strings.end(), texts[i]);
      out[i] = hit != node.negated ? 1.0 : 0.0;
    }
    return out;
  }
  const std::vector<double> a = Evaluate(*node.left, values, n);
  for (std::size_t i = 0; i < n; ++i) {
    // A missing value (NaN) is in no list, and so "not in" every one, as != holds for it.
    const bool hit = !std::isnan(a[i]) && std::binary_search(node.numbers.begin(), node.numbers.end(), a[i]);
    out[i] = hit != node.negated ? 1.0 : 0.0;
  }
  return out;
}

// `contains` / `matches` (and their `not`): a text column against a substring or a regular expression.
std::vector<double> EvaluateMatch(const Node& node, const std::vector<ColumnValues>& values, std::size_t n) {
  std::vector<double> out(n);
  const std::vector<std::string>& texts = values[static_cast<std::size_t>(node.left->column)].texts;
  for (std::size_t i = 0; i < n; ++i) {
    const bool hit = node.regex ? re2::RE2::PartialMatch(texts[i], *node.regex)
                                : texts[i].find(node.text) != std::string::npos;
    out[i] = hit != node.negated ? 1.0 : 0.0;
  }
  return out;
}

std::vector<double> Evaluate(const Node& node, const std::vector<ColumnValues>& values, std::size_t n) {
  switch (node.kind) {
    case Kind::kColumn:
      return values[static_cast<std::size_t>(node.column)].numbers;
    case Kind::kNumber:
      return std::vector<double>(n, node.number);
    case Kind::kString:
      GESWEEP_UNREACHABLE();  // strings are consumed by their comparison
    case Kind::kNot: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      for (double& v : a) v = v != 0.0 ? 0.0 : 1.0;
      return a;
    }
    case Kind::kAnd:
    case Kind::kOr: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      const std::vector<double> b = Evaluate(*node.right, values, n);
      for (std::size_t i = 0; i < n; ++i) {
        a[i] = node.kind == Kind::kAnd ? (a[i] != 0.0 && b[i] != 0.0) : (a[i] != 0.0 || b[i] != 0.0);
      }
      return a;
    }
    case Kind::kTruth: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      for (double& v : a) v = v == 1.0 ? 1.0 : 0.0;
      return a;
    }
    case Kind::kCompare:
      return EvaluateCompare(node, values, n);
    case Kind::kArithmetic: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      const std::vector<double> b = Evaluate(*node.right, values, n);
      const char op = node.text[0];
      for (std::size_t i = 0; i < n; ++i) {
        a[i] = op == '+'   ? a[i] + b[i]
               : op == '-' ? a[i] - b[i]
               : op == '*' ? a[i] * b[i]
               : op == '/' ? a[i] / b[i]
                           : FlooredRemainder(a[i], b[i]);
      }
      return a;
    }
    case Kind::kIn:
      return EvaluateIn(node, values, n);
    case Kind::kMatch:
      return EvaluateMatch(node, values, n);
    case Kind::kNegate: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      for (double& v : a) v = -v;
      return a;
    }
    case Kind::kFunction: {
      std::vector<double> a = Evaluate(*node.left, values, n);
      for (double& v : a) {
        v = node.text == "abs"     ? std::abs(v)
            : node.text == "isnan" ? (std::isnan(v) ? 1.0 : 0.0)
                                   : (std::isfinite(v) ? 1.0 : 0.0);
      }
      return a;
    }
  }
  GESWEEP_UNREACHABLE();
}

}  // namespace

RowFilter::RowFilter() = default;
RowFilter::RowFilter(RowFilter&&) noexcept = default;
RowFilter& RowFilter::operator=(RowFilter&&) noexcept = default;
RowFilter::~RowFilter() = default;

RowFilter RowFilter::Parse(const std::string& text, const ColumnCatalog& catalog, const std::string& flag) {
  Parser parser(text, catalog, flag);
  RowFilter filter;
  filter.root_ = parser.ParseCondition();
  filter.columns_ = parser.columns();
  return filter;
}

void RowFilter::Evaluate(const std::vector<ColumnValues>& values, std::int64_t count,
                         std::vector<char>& keep) const {
  const auto n = static_cast<std::size_t>(count);
  const std::vector<double> result = gesweep::Evaluate(*root_, values, n);
  keep.resize(n);
  for (std::size_t i = 0; i < n; ++i) keep[i] = result[i] != 0.0 ? 1 : 0;
}

}  // namespace gesweep
