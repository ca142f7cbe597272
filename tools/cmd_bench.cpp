// placeholder until written
#include "commands.hpp"
#include <cstdio>
namespace reprise::cli {
int command_bench(int, char**) { std::fputs("reprise bench: not written yet\n", stderr); return 1; }
}
