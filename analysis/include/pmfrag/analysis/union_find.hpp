// Disjoint sets with path halving and union by size: fragments are the connected components of intact bonds.
#pragma once

#include <numeric>
#include <vector>

namespace pmfrag::analysis {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t find(std::size_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a), b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }
  std::size_t size_of(std::size_t a) { return size_[find(a)]; }

 private:
  std::vector<std::size_t> parent_, size_;
};

}  // namespace pmfrag::analysis
