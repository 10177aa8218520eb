// lib/'s one assert hook, for programmer errors only: a broken precondition that no input can cause
// (an index past a fixed size). Bad input is never asserted: it is an UpdateStatus or TableStatus.
// DYNCAL_ASSERT_MODE chooses what DYNCAL_ASSERT(condition) does:
//   0  compiled out (the default with NDEBUG);
//   1  <cassert>'s assert (the default without NDEBUG);
//   2  calls dyncal_assert_failed(file, line, expression), which the port defines and which must not
//      return (port/cortex_m: a semihosting message and exit status 3; dyncal::cortex_m selects it).
#pragma once

#ifndef DYNCAL_ASSERT_MODE
#ifdef NDEBUG
#define DYNCAL_ASSERT_MODE 0
#else
#define DYNCAL_ASSERT_MODE 1
#endif
#endif

#if DYNCAL_ASSERT_MODE == 2
extern "C" [[noreturn]] void dyncal_assert_failed(const char* file, int line, const char* expression) noexcept;
#define DYNCAL_ASSERT(condition) \
  ((condition) ? static_cast<void>(0) : dyncal_assert_failed(__FILE__, __LINE__, #condition))
#elif DYNCAL_ASSERT_MODE == 1
#include <cassert>
#define DYNCAL_ASSERT(condition) assert(condition)
#else
#define DYNCAL_ASSERT(condition) static_cast<void>(0)
#endif
