// Validates an asset through the installed spherechain::playback: prints each finding, exits 1 on an error.
#include <cstdio>

#include <spherechain/playback/validate.h>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: playback_consumer ASSET [MESH]\n");
    return 2;
  }
  namespace pb = spherechain::playback;
  const auto findings = pb::ValidateAssetFile(argv[1], argc > 2 ? argv[2] : "");
  for (const pb::Finding& f : findings)
    std::printf("%s %s %s\n", pb::ToString(f.severity), f.code.c_str(), f.location.ToString().c_str());
  std::printf("findings %zu errors %zu\n", findings.size(), pb::CountErrors(findings));
  return pb::CountErrors(findings) ? 1 : 0;
}
