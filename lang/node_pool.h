// Blocks of one size for one kind of syntax-tree node (ast::Expr, ast::Modification):
// a class's own operator new / delete take them from here instead of from malloc.
//
// A model file's tree is thousands of small nodes made one at a time and, in `check` and
// `run`, never freed (they are left to the process's exit): glibc's malloc then serves
// each from its slow path (~170 instructions; 15 % of the parse of Talos). A block from
// the pool is a free-list pop or a bump in the current chunk. Freed blocks go back on the
// free list of their size; chunks are never returned (the pool only grows to the largest
// tree alive at once) and stay reachable from the pool, so leak checkers count nothing.
// Under AddressSanitizer the nodes come from the global heap, so that a use after free
// is still caught.
//
// One lock serves every pool. A program that forks while other threads may be freeing
// nodes (the Python module: a model dropped on one thread while a sweep forks a worker on
// another) holds it across the fork (NodePoolsLock in pthread_atfork's prepare,
// NodePoolsUnlock in parent and child), so that the child does not start with it taken
// by a thread that does not exist there.
#pragma once

#include <cstddef>
#include <atomic>
#include <new>
#include <thread>

namespace kanesim::lang {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kNodePoolEnabled = false;
#else
inline constexpr bool kNodePoolEnabled = true;
#endif

// Held for a few instructions only (a std::mutex cost more than the work it guards);
// other threads parsing or freeing at the same moment wait their turn.
inline std::atomic_flag g_node_pools_busy = ATOMIC_FLAG_INIT;

inline void NodePoolsLock() {
  while (g_node_pools_busy.test_and_set(std::memory_order_acquire)) std::this_thread::yield();
}
inline void NodePoolsUnlock() { g_node_pools_busy.clear(std::memory_order_release); }

template <std::size_t kSize, std::size_t kAlign>
class NodePool {
  static_assert(kSize >= sizeof(void*) && kAlign <= alignof(std::max_align_t));

 public:
  static void* Allocate() {
    if constexpr (!kNodePoolEnabled) return ::operator new(kSize);
    State& s = Get();
    const Lock lock;
    if (s.free) {
      void* p = s.free;
      s.free = *static_cast<void**>(p);
      return p;
    }
    if (s.next == s.end) NewChunk(s);
    void* p = s.next;
    s.next += kStride;
    return p;
  }
  static void Free(void* p) noexcept {
    if (!p) return;
    if constexpr (!kNodePoolEnabled) return ::operator delete(p);
    State& s = Get();
    const Lock lock;
    *static_cast<void**>(p) = s.free;
    s.free = p;
  }

 private:
  static constexpr std::size_t kStride = (kSize + kAlign - 1) / kAlign * kAlign;
  static constexpr std::size_t kFirstChunk = 64, kMaxChunk = 4096;  // blocks per chunk

  struct Lock {
    Lock() { NodePoolsLock(); }
    ~Lock() { NodePoolsUnlock(); }
    Lock(const Lock&) = delete;
    Lock& operator=(const Lock&) = delete;
  };
  // A chunk: a link to the previous chunk (so every chunk stays reachable), then blocks.
  struct State {
    void* free = nullptr;        // freed blocks, each holding the next one's address
    char* next = nullptr;        // the current chunk's first unused block
    char* end = nullptr;         // its end
    void* chunks = nullptr;      // the last chunk (its first word links the one before)
    std::size_t blocks = kFirstChunk;  // blocks of the next chunk (doubled up to kMaxChunk)
  };
  static State& Get() {
    static State* state = new State;  // never destroyed: nodes left to the exit may be freed after main
    return *state;
  }
  static void NewChunk(State& s) {
    constexpr std::size_t kHeader = (sizeof(void*) + kAlign - 1) / kAlign * kAlign;
    char* c = static_cast<char*>(::operator new(kHeader + s.blocks * kStride));
    *reinterpret_cast<void**>(c) = s.chunks;
    s.chunks = c;
    s.next = c + kHeader;
    s.end = s.next + s.blocks * kStride;
    if (s.blocks < kMaxChunk) s.blocks *= 2;
  }
};

// operator new / delete for a class T whose objects come from NodePool (declare inside T).
#define KANESIM_POOLED_NODE(T)                                                                  \
  static void* operator new(std::size_t n) {                                                   \
    return n == sizeof(T) ? ::kanesim::lang::NodePool<sizeof(T), alignof(T)>::Allocate()        \
                          : ::operator new(n);                                                  \
  }                                                                                            \
  static void operator delete(void* p, std::size_t n) noexcept {                               \
    if (n == sizeof(T)) ::kanesim::lang::NodePool<sizeof(T), alignof(T)>::Free(p);              \
    else ::operator delete(p);                                                                  \
  }

// An allocator for node-based containers (std::map): each node, allocated one at a time,
// comes from NodePool; anything else from the global heap. Stateless, so containers
// using it move and swap as with std::allocator.
template <class T>
struct PoolAllocator {
  using value_type = T;
  PoolAllocator() = default;
  template <class U>
  PoolAllocator(const PoolAllocator<U>&) noexcept {}  // NOLINT: rebinding is implicit
  T* allocate(std::size_t n) {
    if (n == 1) return static_cast<T*>(NodePool<sizeof(T), alignof(T)>::Allocate());
    return static_cast<T*>(::operator new(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n == 1) NodePool<sizeof(T), alignof(T)>::Free(p);
    else ::operator delete(p);
  }
  template <class U>
  bool operator==(const PoolAllocator<U>&) const noexcept { return true; }
  template <class U>
  bool operator!=(const PoolAllocator<U>&) const noexcept { return false; }
};

}  // namespace kanesim::lang
