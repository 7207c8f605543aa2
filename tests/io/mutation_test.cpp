// Robustness: damaged files either parse or raise InputError, never anything
// else (no crash, no other exception, no hang). Every format and flavour, cut
// at many lengths and with bytes overwritten at many offsets.
#include <catch2/catch.hpp>

#include <random>

#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

/// Parses `bytes`; returns false on InputError. Any other exception fails the test.
bool parses(const std::string& bytes, Format f) {
  try {
    parse_soup(bytes, f, "mutant");
    return true;
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find('\n') == std::string::npos);
    return false;
  }
}

}  // namespace

TEST_CASE("read: truncated and corrupted files raise InputError or parse", "[io]") {
  Soup s = read_soup(test::fixture("dirty_box.obj"));  // groups, several patches
  struct Flavour {
    Format format;
    bool ascii;
    const char* name;
  };
  const Flavour flavours[] = {{Format::off, true, "off"},       {Format::obj, true, "obj"},
                              {Format::stl, true, "ascii stl"}, {Format::stl, false, "binary stl"},
                              {Format::ply, true, "ascii ply"}, {Format::ply, false, "binary ply"}};
  std::mt19937 rng(2024);
  const char junk[] = {'\0', '\n', ' ', '-', '9', 'x', '#', '/', '\xff', 'e', '.', '+'};
  for (const Flavour& fl : flavours) {
    INFO(fl.name);
    const std::string good = serialize_soup(s, fl.format, fl.ascii);
    REQUIRE(parses(good, fl.format));
    int rejected = 0;
    // Every truncation length near the start and the end, and a sample in between.
    std::vector<std::size_t> cuts;
    for (std::size_t n = 0; n < std::min<std::size_t>(good.size(), 200); ++n) cuts.push_back(n);
    for (std::size_t n = good.size() > 200 ? good.size() - 200 : 0; n < good.size(); ++n) cuts.push_back(n);
    std::uniform_int_distribution<std::size_t> pos(0, good.size() - 1);
    for (int k = 0; k < 300; ++k) cuts.push_back(pos(rng));
    // Formats that declare their size reject every cut: binary ones anywhere,
    // text ones anywhere before their last line (a cut inside the last line
    // can leave a shorter, valid number). OBJ declares nothing: a cut at a
    // line boundary is indistinguishable from a smaller file.
    const bool binary = !fl.ascii;
    const std::size_t last_line = good.rfind('\n', good.size() - 2) + 1;
    for (std::size_t n : cuts) {
      const bool ok = parses(good.substr(0, n), fl.format);
      rejected += !ok;
      if (fl.format != Format::obj && (binary || n < last_line)) {
        INFO("cut at " << n << " of " << good.size());
        CHECK_FALSE(ok);
      }
    }
    // Single and multiple overwritten bytes.
    std::uniform_int_distribution<int> pick(0, sizeof junk - 1);
    for (int k = 0; k < 1500; ++k) {
      std::string bad = good;
      const int hits = 1 + k % 3;
      for (int h = 0; h < hits; ++h) bad[pos(rng)] = junk[pick(rng)];
      parses(bad, fl.format);
    }
    CHECK(rejected > 0);  // truncations are noticed, not read partially
  }
}
