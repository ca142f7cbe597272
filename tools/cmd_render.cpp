// placeholder until written
#include "commands.hpp"
#include <cstdio>
namespace reprise::cli {
int command_render(int, char**) { std::fputs("reprise render: not written yet\n", stderr); return 1; }
int command_scenes(int, char**) { return 1; }
}
