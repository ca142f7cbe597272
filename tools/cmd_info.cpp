// placeholder until written
#include "commands.hpp"
#include <cstdio>
namespace reprise::cli {
int command_info(int, char**) { std::fputs("reprise info: not written yet\n", stderr); return 1; }
}
