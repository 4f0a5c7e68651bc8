#pragma once
/// The depth-first stack of the branch-and-bound searches (in memory, query_distance.cpp; over
/// the out-of-core top tree, out_of_core.cpp): a node's children go on in descending lower
/// bound, so that the nearest is popped first.

namespace ebp {

/// Pushes kids[0, nk) (nk <= 8; any item type with a `bound`) onto stack[sp...], sorted in
/// descending bound (an insertion sort, stable: equal bounds keep their octant order).
template <class Item>
inline void push_nearest_first(Item* kids, int nk, Item* stack, int& sp) {
  for (int a = 1; a < nk; ++a) {
    Item x = kids[a];
    int b = a - 1;
    while (b >= 0 && kids[b].bound < x.bound) {
      kids[b + 1] = kids[b];
      --b;
    }
    kids[b + 1] = x;
  }
  for (int a = 0; a < nk; ++a) stack[sp++] = kids[a];
}

}  // namespace ebp
