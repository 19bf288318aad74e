#include "text_table.hpp"

#include <algorithm>
#include <cstdio>

namespace canemu::cli {

TextTable::TextTable(std::vector<Column> columns, std::string indent)
    : columns_(std::move(columns)), indent_(std::move(indent)) {}

void TextTable::add(std::vector<std::string> cells) {
  cells.resize(columns_.size());
  rows_.push_back(std::move(cells));
}

std::string TextTable::text() const {
  std::vector<std::size_t> widths;
  for (const Column& c : columns_) {
    widths.push_back(std::max(c.min_width, c.header.size()));
  }
  for (const auto& row : rows_) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      widths[k] = std::max(widths[k], row[k].size());
    }
  }
  std::string out;
  const auto line = [&](const auto& cell_of) {
    std::string row = indent_;
    for (std::size_t k = 0; k < columns_.size(); ++k) {
      const std::string& cell = cell_of(k);
      const std::size_t pad = widths[k] - std::min(widths[k], cell.size());
      if (k > 0) {
        row.append(columns_[k].gap, ' ');
      }
      if (columns_[k].align == Align::right) {
        row.append(pad, ' ');
        row += cell;
      } else {
        row += cell;
        row.append(pad, ' ');
      }
    }
    row.erase(row.find_last_not_of(' ') + 1);
    out += row + "\n";
  };
  line([&](std::size_t k) -> const std::string& { return columns_[k].header; });
  for (const auto& r : rows_) {
    line([&](std::size_t k) -> const std::string& { return r[k]; });
  }
  return out;
}

void TextTable::print() const {
  std::fputs(text().c_str(), stdout);
}

}  // namespace canemu::cli
