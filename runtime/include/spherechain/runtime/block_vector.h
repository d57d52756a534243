// spherechain runtime — BlockVector: the narrow phase's arrays, on the heap while they are built and in
// one block (a Model's or a Workspace's, or a NarrowPhaseModel's own) once they are.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

namespace spherechain::runtime {

/// A bump region of one block that BlockAllocators carve from. It is stored at the start of the block
/// itself, so its address never changes when the object owning the block is moved. Carving is done in
/// 64-byte steps from `begin`; once the block is built, `cursor` is set to `end` (sealed).
struct BlockArena {
  unsigned char* cursor = nullptr;  ///< next free byte
  unsigned char* begin = nullptr;   ///< first byte after this header (64-byte aligned)
  unsigned char* end = nullptr;     ///< one past the block's last byte
  uint32_t fallbacks = 0;           ///< allocations that did not fit and went to the heap (0 when sized right)

  static constexpr size_t kAlign = 64;
  static constexpr size_t AlignUp(size_t n) { return (n + kAlign - 1) & ~(kAlign - 1); }
  /// Bytes a block needs to hold this header and arrays of `payload` bytes (Σ AlignUp of each array's
  /// capacity in bytes) at any 16-byte aligned address.
  static constexpr size_t BlockBytes(size_t payload) { return kAlign - 16 + AlignUp(sizeof(BlockArena)) + payload; }

  /// Places the header at the start of `memory` (16-byte aligned, `bytes` long) and returns it.
  static BlockArena* Create(void* memory, size_t bytes) {
    unsigned char* m = static_cast<unsigned char*>(memory);
    const size_t lead = (kAlign - reinterpret_cast<uintptr_t>(m) % kAlign) % kAlign;
    BlockArena* a = new (m + lead) BlockArena{};
    a->begin = a->cursor = m + lead + AlignUp(sizeof(BlockArena));
    a->end = m + bytes;
    return a;
  }
  /// `n` bytes, 64-byte aligned, or null when the block is full.
  void* Carve(size_t n) {
    if (static_cast<size_t>(end - cursor) < AlignUp(n)) return nullptr;
    void* p = cursor;
    cursor += AlignUp(n);
    return p;
  }
  bool Owns(const void* p) const { return p >= begin && p < end; }
};

/// std::allocator-compatible allocator over a BlockArena (null: the heap). Allocations that fit are
/// carved from the block and never freed one by one (the block is freed whole); the rest, and every
/// allocation without an arena, go to the heap. Propagates on copy, move and swap.
template <class T>
struct BlockAllocator {
  using value_type = T;
  using propagate_on_container_copy_assignment = std::true_type;
  using propagate_on_container_move_assignment = std::true_type;
  using propagate_on_container_swap = std::true_type;

  BlockArena* arena = nullptr;

  BlockAllocator() = default;
  explicit BlockAllocator(BlockArena* a) : arena(a) {}
  template <class U>
  BlockAllocator(const BlockAllocator<U>& o) : arena(o.arena) {}  // NOLINT: rebinding is implicit

  T* allocate(size_t n) {
    if (arena) {
      if (void* p = arena->Carve(n * sizeof(T))) return static_cast<T*>(p);
      ++arena->fallbacks;
    }
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{alignof(T) > 16 ? alignof(T) : 16}));
  }
  void deallocate(T* p, size_t) {
    if (arena && arena->Owns(p)) return;
    ::operator delete(p, std::align_val_t{alignof(T) > 16 ? alignof(T) : 16});
  }
  template <class U>
  bool operator==(const BlockAllocator<U>& o) const { return arena == o.arena; }
  template <class U>
  bool operator!=(const BlockAllocator<U>& o) const { return arena != o.arena; }
};

/// The narrow phase's array type: a std::vector whose storage is the heap or a block (BlockAllocator).
template <class T>
using BlockVector = std::vector<T, BlockAllocator<T>>;

/// Frees a block made by AllocateBlock.
struct BlockDeleter {
  void operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{BlockArena::kAlign}); }
};
/// An owned block (null: none, or the arrays live in someone else's).
using BlockPtr = std::unique_ptr<unsigned char[], BlockDeleter>;
/// A block of `bytes`, 64-byte aligned. Throws std::bad_alloc.
inline BlockPtr AllocateBlock(size_t bytes) {
  return BlockPtr(new (std::align_val_t{BlockArena::kAlign}) unsigned char[bytes]);
}

/// Bytes `v` takes once moved into a block (its capacity, rounded up to the block's 64-byte steps).
template <class T>
size_t BlockBytesOf(const BlockVector<T>& v) {
  return BlockArena::AlignUp(v.capacity() * sizeof(T));
}

/// Moves `v`'s elements into storage carved from `arena` with the same capacity (so what stays within
/// the capacity never reallocates) and frees its previous storage.
template <class T>
void MoveIntoBlock(BlockVector<T>& v, BlockArena* arena) {
  BlockVector<T> packed{BlockAllocator<T>{arena}};
  packed.reserve(v.capacity());
  packed.assign(v.begin(), v.end());
  v = std::move(packed);
}

/// Gives `v` an empty storage of `arena`'s (what it then allocates is carved from the block).
template <class T>
void UseBlock(BlockVector<T>& v, BlockArena* arena) {
  v = BlockVector<T>{BlockAllocator<T>{arena}};
}

}  // namespace spherechain::runtime
