// placeholder until written
#include "commands.hpp"
#include <cstdio>
namespace reprise::cli {
int command_metrics(int, char**) { std::fputs("reprise metrics: not written yet\n", stderr); return 1; }
}
