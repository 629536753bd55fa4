// "Did you mean ...?" for unknown names (inputs, functions, frames): the candidates
// closest to a misspelt name.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace robodiff::language {

// Up to max_count candidates close to `name`, nearest first (then by name). Close means,
// comparing case-insensitively, an optimal-string-alignment (Damerau-Levenshtein with
// adjacent transpositions) distance of at most max(2, length of name / 3), or one
// containing the other ('hand' -> 'panda_hand'; the shorter at least 3 characters). A candidate equal to `name` is not
// suggested; duplicates are suggested once. Names and candidates are compared on their
// first 256 characters only, so the work is bounded whatever their length.
std::vector<std::string> closestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t max_count = 3);

// "" when nothing is close, else " (did you mean 'a', 'b'?)", to append to a message.
std::string didYouMean(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace robodiff::language
