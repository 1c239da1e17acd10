#include "test_util.h"

#include <array>
#include <cstdio>
#include <sys/wait.h>

namespace linesurf::test {

CliResult runCli(const std::string& args) {
  CliResult r;
  std::string cmd = std::string(LINESURF_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace linesurf::test
