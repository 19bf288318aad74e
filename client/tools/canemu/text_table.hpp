// Tables as canemu prints them: a header row, then rows; each column as wide as its widest cell
// and at least its minimum, names left-aligned, numbers right-aligned, no blanks at a row's end.
// A long name widens its column instead of pushing the rest of its row out of line.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace canemu::cli {

class TextTable {
 public:
  enum class Align { left, right };
  struct Column {
    std::string header;
    Align align = Align::left;
    std::size_t min_width = 0;
    std::size_t gap = 1;  // blanks before the column (none before the first)
  };

  // `indent` goes before every row, the header's too.
  explicit TextTable(std::vector<Column> columns, std::string indent = "");

  // A row of one cell per column (missing ones are empty).
  void add(std::vector<std::string> cells);

  // The header and the rows, each ending in '\n'.
  std::string text() const;
  // text() on standard output.
  void print() const;

 private:
  std::vector<Column> columns_;
  std::string indent_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace canemu::cli
