// Where the tests find the program, the test data and the sources. Defined in paths.cpp, the one
// test file compiled with the checkout's paths (tests/CMakeLists.txt), so that every other test file
// compiles to the same object in any clone and a compiler cache shares it.
#pragma once

namespace trubal::test {
extern const char* const kTrubalExe;   // the trubal executable of this build
extern const char* const kTestDir;     // tests/ of the checkout
extern const char* const kSourceDir;   // the checkout's root
}  // namespace trubal::test

#define TRUBAL_EXE (::trubal::test::kTrubalExe)
#define TRUBAL_TEST_DIR (::trubal::test::kTestDir)
#define TRUBAL_SOURCE_DIR (::trubal::test::kSourceDir)
