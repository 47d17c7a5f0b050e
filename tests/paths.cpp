// The paths of paths.hpp, given by tests/CMakeLists.txt for this file alone.
#include "paths.hpp"

namespace trubal::test {
const char* const kTrubalExe = TRUBAL_TEST_EXE_PATH;
const char* const kTestDir = TRUBAL_TEST_DIR_PATH;
const char* const kSourceDir = TRUBAL_SOURCE_DIR_PATH;
}  // namespace trubal::test
