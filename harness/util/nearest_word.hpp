#pragma once
/// The nearest of a few known words to a misspelt one, for "did you mean ...?" in messages about
/// unknown keys and parameters (a suite file, a method's or a query kind's parameters).
#include <algorithm>
#include <string>
#include <vector>

namespace bvhbench {

/// Levenshtein distance: insertions, deletions and substitutions, each counting one.
inline std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substituted = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substituted});
    }
  }
  return row[b.size()];
}

/// The word of `known` closest to `word`, or "" when none is close enough to be what was meant
/// (more than a third of the longer word's letters changed, and more than two).
inline std::string nearest_word(const std::string& word, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = 0;
  for (const std::string& k : known) {
    const std::size_t d = edit_distance(word, k);
    const std::size_t allowed = std::max<std::size_t>(2, std::max(word.size(), k.size()) / 3);
    if (d <= allowed && (best.empty() || d < best_distance)) {
      best = k;
      best_distance = d;
    }
  }
  return best;
}

}  // namespace bvhbench
