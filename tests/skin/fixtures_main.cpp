// lodkit_fixtures OUT_DIR [MAN_OFF]: writes the skinned test characters (humanoid.glb,
// humanoid_baked.glb, and man.glb when man.off is there) for the benchmarks and the README.
#include <cstdio>
#include <cstring>
#include <exception>

#include "lodkit/error.h"
#include "skin/fixtures.h"

int main(int argc, char** argv) {
  // An option is never a folder name here: `--help` printed the usage, not a folder called --help.
  const bool option = argc >= 2 && argv[1][0] == '-';
  if (argc < 2 || argc > 3 || option) {
    const bool help = option && (std::strcmp(argv[1], "-h") == 0 || std::strcmp(argv[1], "--help") == 0);
    std::fprintf(help ? stdout : stderr, "usage: lodkit_fixtures OUT_DIR [MAN_OFF]   (MAN_OFF defaults to %s/man.off)\n",
                 LODKIT_CORPUS_DIR);
    return help ? 0 : 1;
  }
  const std::filesystem::path man = argc > 2 ? std::filesystem::path(argv[2]) : std::filesystem::path(LODKIT_CORPUS_DIR) / "man.off";
  try {
    for (const auto& path : lod::fixtures::write_fixtures(argv[1], man)) std::printf("%s\n", path.string().c_str());
    std::error_code ec;
    if (!std::filesystem::is_regular_file(man, ec)) std::fprintf(stderr, "lodkit_fixtures: %s is absent, man.glb skipped\n", man.string().c_str());
  } catch (const lod::Error& e) {
    std::fprintf(stderr, "lodkit_fixtures: %s\n", e.what());
    return e.category() == lod::ErrorCategory::usage ? 1 : e.category() == lod::ErrorCategory::bad_input ? 2 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit_fixtures: %s\n", e.what());
    return 3;
  }
  return 0;
}
