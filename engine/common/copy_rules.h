#pragma once
/// Declarations of how a class that owns a resource (a file handle, a lock, signal handlers, zlib's
/// state) may be copied or moved, said once. Each macro stands in a class's public section.

// The macro argument is a class name in declarations, where parentheses cannot stand.
// NOLINTBEGIN(bugprone-macro-parentheses)

/// The class is not copyable: its copy constructor and copy assignment are deleted (it has no move
/// either, unless it declares one).
#define GESWEEP_NO_COPY(Class)  \
  Class(const Class&) = delete; \
  Class& operator=(const Class&) = delete

/// The class moves by construction only (a factory returns it): it declares a noexcept move
/// constructor, which it defines; move and copy assignment and the copy constructor are deleted.
#define GESWEEP_MOVE_CONSTRUCT_ONLY(Class) \
  Class(Class&& other) noexcept;           \
  Class& operator=(Class&&) = delete;      \
  GESWEEP_NO_COPY(Class)

// NOLINTEND(bugprone-macro-parentheses)
