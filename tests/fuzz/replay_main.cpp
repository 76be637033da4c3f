// stride-fuzz-replay FILE|DIR...: every file (a folder's in name order) through the message
// fuzzer's LLVMFuzzerTestOneInput (fuzz_messages.cpp), without libFuzzer, so that any compiler
// builds it: the ctest fuzz_corpus_replay runs the seed corpus through the real handlers, and a
// crash file a fuzzing run left can be replayed under a debugger. Each input sits in a heap block
// of exactly its size, as libFuzzer gives it, so a sanitizer sees a read past its end. Exit status:
// 0 when every input ran, 2 on a usage error or an unreadable file (a finding aborts).

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "fuzz_channels.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    std::fprintf(argc < 2 ? stderr : stdout, "usage: %s FILE|DIR...\n", argv[0]);
    return argc < 2 ? 2 : 0;
  }
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path p = argv[i];
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> in_dir;
      for (const fs::directory_entry& e : fs::directory_iterator(p))
        if (e.is_regular_file()) in_dir.push_back(e.path());
      std::sort(in_dir.begin(), in_dir.end());
      files.insert(files.end(), in_dir.begin(), in_dir.end());
    } else if (fs::is_regular_file(p, ec)) {
      files.push_back(p);
    } else {
      std::fprintf(stderr, "stride-fuzz-replay: no file or folder %s\n", argv[i]);
      return 2;
    }
  }
  long bytes = 0;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<char> content{std::istreambuf_iterator<char>(in),
                                    std::istreambuf_iterator<char>()};
    if (!in.good() && !in.eof()) {
      std::fprintf(stderr, "stride-fuzz-replay: cannot read %s\n", f.c_str());
      return 2;
    }
    const std::size_t n = content.size();
    const std::unique_ptr<std::uint8_t[]> input(new std::uint8_t[n > 0 ? n : 1]);
    std::memcpy(input.get(), content.data(), n);
    LLVMFuzzerTestOneInput(input.get(), n);
    bytes += static_cast<long>(n);
  }
  std::printf("stride-fuzz-replay: %zu inputs (%ld bytes) through the handlers\n%s\n", files.size(),
              bytes, stride::fuzz::handledSummary().c_str());
  return 0;
}
