// The test suite's own hygiene: every TEST_CASE name must reach ctest whole.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>

TEST_CASE("tests: no test case name holds a semicolon (ctest would split it into names that run nothing)",
          "[tests]") {
  // catch_discover_tests hands the names to CMake, whose lists are separated by semicolons: a name
  // with one became two ctest tests, each a filter that matched no test case and passed. Five
  // test cases once ran in no ctest run that way (one of them failed when run).
  namespace fs = std::filesystem;
  const std::regex test_case(R"re(TEST_CASE\(\s*"([^"]*)")re");
  int files = 0, names = 0;
  for (const char* folder : {"unit", "validation"}) {
    const fs::path dir = fs::path(TRUBAL_TEST_DIR) / folder;
    if (!fs::exists(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() != ".cpp") continue;
      ++files;
      std::ifstream in(entry.path());
      const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
      for (std::sregex_iterator it(text.begin(), text.end(), test_case), end; it != end; ++it) {
        ++names;
        INFO(entry.path().filename().string() << ": " << (*it)[1].str());
        CHECK((*it)[1].str().find(';') == std::string::npos);
      }
    }
  }
  CHECK(files > 30);
  CHECK(names > 200);
}
