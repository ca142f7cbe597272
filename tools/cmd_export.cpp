// placeholder until written
#include "commands.hpp"
#include <cstdio>
namespace reprise::cli {
int command_export(int, char**) { std::fputs("reprise export: not written yet\n", stderr); return 1; }
}
