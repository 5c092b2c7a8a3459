// Sizing a buffer whose contents the caller rewrites after every resize (a frame's tile
// records, the backward's gradient slots). std::vector::resize past the capacity copies the
// old contents into the new storage and holds both until it is done: at 10^6 Gaussians a
// frame's per-entry buffers are hundreds of MB, and the copy was the peak of a training run
// (issue 15). ResizeScratch releases the old storage first.
#pragma once

#include <cstddef>
#include <vector>

namespace hdr4d {

// Makes *v hold n elements, with unspecified values (all of them are to be written). Growth
// past the capacity leaves 1/4 headroom, so that buffers following the views' overlaps
// reallocate rarely.
template <typename T>
void ResizeScratch(std::vector<T>* v, std::size_t n) {
  if (n > v->capacity()) {
    std::vector<T>().swap(*v);
    v->reserve(n + n / 4);
  }
  v->resize(n);
}

}  // namespace hdr4d
