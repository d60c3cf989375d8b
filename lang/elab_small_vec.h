// A vector of trivially copyable elements that keeps up to N of them inside the object:
// the elaborator's values are mostly scalars, 3-vectors and 3x3 matrices, and a heap
// allocation per value (they are made, copied and dropped by the hundred per link of a
// chain) cost more than the evaluation itself. Beyond N elements it behaves like
// std::vector. Only what the elaborator uses is here.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <new>
#include <type_traits>

namespace kanesim::lang::elab {

template <class T, std::size_t N>
class SmallVec {
  static_assert(std::is_trivially_copyable_v<T>, "SmallVec holds trivially copyable elements");

 public:
  using value_type = T;
  using iterator = T*;
  using const_iterator = const T*;

  SmallVec() = default;
  SmallVec(std::initializer_list<T> il) { assign(il.begin(), il.end()); }
  SmallVec(const SmallVec& o) { assign(o.begin(), o.end()); }
  SmallVec(SmallVec&& o) noexcept { Steal(o); }
  SmallVec& operator=(const SmallVec& o) {
    if (this != &o) assign(o.begin(), o.end());
    return *this;
  }
  SmallVec& operator=(SmallVec&& o) noexcept {
    if (this != &o) {
      Release();
      Steal(o);
    }
    return *this;
  }
  SmallVec& operator=(std::initializer_list<T> il) {
    assign(il.begin(), il.end());
    return *this;
  }
  ~SmallVec() { Release(); }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T& back() { return data_[size_ - 1]; }
  const T& back() const { return data_[size_ - 1]; }

  void reserve(std::size_t n) {
    if (n <= cap_) return;
    if (n > UINT32_MAX) throw std::bad_alloc();  // sizes are 32-bit (the elaborator caps arrays far below)
    T* p = static_cast<T*>(std::malloc(n * sizeof(T)));
    if (!p) throw std::bad_alloc();
    if (size_) std::memcpy(p, data_, size_ * sizeof(T));
    if (data_ != inline_) std::free(data_);
    data_ = p;
    cap_ = static_cast<std::uint32_t>(n);
  }
  void clear() { size_ = 0; }
  void pop_back() { --size_; }
  void push_back(const T& x) {
    if (size_ == cap_) {
      const T copy = x;  // x may live in this vector
      reserve(std::size_t{cap_} * 2);
      data_[size_++] = copy;
      return;
    }
    data_[size_++] = x;
  }
  void resize(std::size_t n, const T& x = T()) {
    reserve(n);
    for (std::size_t i = size_; i < n; ++i) data_[i] = x;
    size_ = static_cast<std::uint32_t>(n);
  }
  void assign(std::size_t n, const T& x) {
    const T copy = x;
    size_ = 0;
    resize(n, copy);
  }
  template <class It, class = std::enable_if_t<!std::is_integral_v<It>>>
  void assign(It first, It last) {
    const std::size_t n = static_cast<std::size_t>(std::distance(first, last));
    if (n > cap_) {
      // Not from this vector: a vector never assigns a range of its own beyond its size.
      size_ = 0;
      reserve(n);
    }
    std::size_t i = 0;
    for (It it = first; it != last; ++it) data_[i++] = *it;
    size_ = static_cast<std::uint32_t>(n);
  }
  // Appends [first, last) at `pos`, which must be end() (the only use).
  template <class It>
  void insert(const T* pos, It first, It last) {
    (void)pos;
    const std::size_t n = static_cast<std::size_t>(std::distance(first, last));
    if (size_ + n > cap_) {
      // [first, last) may point into this vector: copy it out before growing.
      T* tmp = static_cast<T*>(std::malloc(std::max<std::size_t>(n, 1) * sizeof(T)));
      if (!tmp) throw std::bad_alloc();
      std::size_t i = 0;
      for (It it = first; it != last; ++it) tmp[i++] = *it;
      reserve(std::max(size_ + n, std::size_t{cap_} * 2));
      std::memcpy(data_ + size_, tmp, n * sizeof(T));
      std::free(tmp);
    } else {
      std::size_t i = size_;
      for (It it = first; it != last; ++it) data_[i++] = *it;
    }
    size_ += static_cast<std::uint32_t>(n);
  }

  friend bool operator==(const SmallVec& a, const SmallVec& b) {
    return a.size_ == b.size_ && std::equal(a.begin(), a.end(), b.begin());
  }
  friend bool operator!=(const SmallVec& a, const SmallVec& b) { return !(a == b); }

 private:
  void Release() {
    if (data_ != inline_) std::free(data_);
    data_ = inline_;
    size_ = 0;
    cap_ = N;
  }
  // Takes o's elements; o is left empty (its storage inline).
  void Steal(SmallVec& o) {
    if (o.data_ == o.inline_) {
      data_ = inline_;
      cap_ = N;
      if (o.size_) std::memcpy(inline_, o.inline_, o.size_ * sizeof(T));
      size_ = o.size_;
    } else {
      data_ = o.data_;
      cap_ = o.cap_;
      size_ = o.size_;
      o.data_ = o.inline_;
      o.cap_ = N;
    }
    o.size_ = 0;
  }

  // 32-bit size and capacity: a scalar, 3-vector or 3x3 matrix value stays within a few
  // words (values are copied by the hundred per link).
  T* data_ = inline_;
  std::uint32_t size_ = 0;
  std::uint32_t cap_ = N;
  T inline_[N];
};

}  // namespace kanesim::lang::elab
