#pragma once
// The subcommands of `reprise`; each takes the arguments after its name.

namespace reprise::cli {

int command_render(int argc, char** argv);
int command_scenes(int argc, char** argv);
int command_info(int argc, char** argv);
int command_metrics(int argc, char** argv);
int command_export(int argc, char** argv);
int command_bench(int argc, char** argv);
int command_fruc(int argc, char** argv);
int command_stereo(int argc, char** argv);

}  // namespace reprise::cli
