#pragma once
// The subcommands of `reprise`; each takes the arguments after its name.

#include <string>

#include "reprise/core/status.hpp"

namespace reprise::cli {

int command_render(int argc, char** argv);
int command_scenes(int argc, char** argv);
int command_info(int argc, char** argv);
int command_metrics(int argc, char** argv);
int command_export(int argc, char** argv);
int command_bench(int argc, char** argv);
int command_fruc(int argc, char** argv);
int command_stereo(int argc, char** argv);
int command_encode(int argc, char** argv);
int command_decode(int argc, char** argv);
int command_serve(int argc, char** argv);
int command_connect(int argc, char** argv);
int command_upsample(int argc, char** argv);
int command_batch(int argc, char** argv);

// `reprise info FILE.rps`: the stream's size, packets and bit rate.
Status describe_stream(const std::string& path);

}  // namespace reprise::cli
