// The rdtf command line as users and scripts run it.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <sstream>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace rdtf {
namespace {

std::string cli() { return "'" + testing::cli_path() + "'"; }

std::string fixture(const std::string& name) {
  return "'" + (testing::data_dir() / "blender" / name).string() + "'";
}

TEST(Cli, ConvertWritesBesideTheInputByDefault) {
  testing::TempDir folder;
  std::filesystem::copy_file(testing::data_dir() / "blender" / "two_cylinder.gltf", folder / "two_cylinder.gltf");
  std::filesystem::copy_file(testing::data_dir() / "blender" / "two_cylinder.bin", folder / "two_cylinder.bin");
  const auto run = testing::run_command(cli() + " convert '" + (folder / "two_cylinder.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  const auto output = folder / "two_cylinder.rdtf.gltf";
  ASSERT_TRUE(std::filesystem::exists(output));
  const auto document = nlohmann::json::parse(testing::read_file(output));
  EXPECT_TRUE(document["extras"]["RDTF"]["nodes"].is_array());
  EXPECT_NE(run.err.find("2 links, 1 joints"), std::string::npos) << run.err;
}

TEST(Cli, ConvertToGlbByFlagOrByName) {
  testing::TempDir folder;
  const auto by_flag = folder / "a.bin.out";
  auto run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " --glb -o '" + by_flag.string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(testing::read_file(by_flag).substr(0, 4), "glTF");
  const auto by_name = folder / "robot.glb";
  run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" + by_name.string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(testing::read_file(by_name).substr(0, 4), "glTF");
  // The name's case does not matter (the loader and rdtfd read ARM.GLB as a GLB): it was written as
  // JSON with a .bin beside it.
  const auto upper = folder / "ARM.GLB";
  run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" + upper.string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(testing::read_file(upper).substr(0, 4), "glTF");
  const auto imported = folder / "R2.Glb";
  run = testing::run_command(cli() + " import '" + (testing::data_dir() / "robots" / "r2d2.urdf").string() + "' -o '" +
                             imported.string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(testing::read_file(imported).substr(0, 4), "glTF");
  for (const auto& entry : std::filesystem::directory_iterator(folder.path())) {
    EXPECT_NE(entry.path().extension(), ".bin") << entry.path();
  }
}

TEST(Cli, InspectPrintsLinksJointsAndMass) {
  const auto run = testing::run_command(cli() + " inspect " + fixture("arm3.gltf"));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  for (const char* text : {"base_link", "upper_arm", "forearm", "shoulder", "elbow", "revolute",
                           "mass", "inertia", "centre of mass"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text << "\n" << run.out;
  }
}

// A node name is the input's to choose: a newline or a terminal escape in it must not forge a
// line of the CLI's output or drive the terminal that shows it.
TEST(Cli, NamesInDiagnosticsAreEscaped) {
  testing::TempDir folder;
  auto document = nlohmann::json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  for (auto& node : document["nodes"]) {
    if (node["name"] == "elbow") {
      node["name"] = "el\nbow\x1b[2J";
      node["extras"]["rdtf_lower"] = -90;  // JOINT_LIMITS_IMPLAUSIBLE names the node.
    }
  }
  testing::write_file(folder / "arm3.gltf", document.dump());
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", folder / "arm3.bin");
  const auto run = testing::run_command(cli() + " convert '" + (folder / "arm3.gltf").string() + "' -o '" +
                                        (folder / "out.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("JOINT_LIMITS_IMPLAUSIBLE"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("el\\nbow\\x1b[2J"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find('\x1b'), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("el\nbow"), std::string::npos) << run.err;
  // The table of rdtf inspect too.
  const auto table = testing::run_command(cli() + " inspect '" + (folder / "arm3.gltf").string() + "'");
  EXPECT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("el\\nbow\\x1b[2J  revolute"), std::string::npos) << table.out;
  EXPECT_EQ(table.out.find('\x1b'), std::string::npos) << table.out;
}

TEST(Cli, InspectJsonIsMachineReadable) {
  const auto run = testing::run_command(cli() + " inspect --json " + fixture("arm3.gltf"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  ASSERT_EQ(summary["links"].size(), 3u);
  EXPECT_EQ(summary["links"][0]["name"], "base_link");
  // base_link is a 0.2 m cube (float32 vertices): 8 kg at 1000 kg/m^3.
  EXPECT_NEAR(summary["links"][0]["mass"].get<double>(), 8.000000357627874, 8e-6);
  EXPECT_EQ(summary["links"][0]["inertia"].size(), 6u);
  EXPECT_EQ(summary["joints"][0]["name"], "shoulder");
  EXPECT_EQ(summary["joints"][0]["type"], "revolute");
  // Limits as given: arm3's shoulder has a range and no effort or speed limit, which is no 0.
  EXPECT_EQ(summary["joints"][0]["limits"], (nlohmann::json{{"lower", -1.57}, {"upper", 1.57}}));
}

// A model that does not convert: --json still prints JSON on stdout (a script parsing it got
// nothing), with every error and its place as fields; exit 2.
TEST(Cli, JsonOfAModelThatDoesNotConvertHoldsItsErrors) {
  testing::TempDir dir;
  const auto blender = testing::data_dir() / "blender";
  nlohmann::json document = nlohmann::json::parse(testing::read_file(blender / "arm3.gltf"));
  for (nlohmann::json& node : document["nodes"]) {
    if (node.value("name", "") == "elbow") node["extras"]["rdtf_axis"] = {0, 0, 0};
  }
  testing::write_file(dir / "arm3.gltf", document.dump());
  std::filesystem::copy_file(blender / "arm3.bin", dir / "arm3.bin");
  for (const std::string command : {"inspect", "validate"}) {
    const auto run = testing::run_command(cli() + " " + command + " --json " + (dir / "arm3.gltf").string());
    EXPECT_EQ(run.exit_code, 2) << command;
    const nlohmann::json out = nlohmann::json::parse(run.out);
    EXPECT_EQ(out["converted"], false) << command;
    const nlohmann::json& errors = out[command == "inspect" ? "diagnostics" : "conversionDiagnostics"];
    ASSERT_FALSE(errors.empty()) << command << ": " << out.dump();
    const auto axis = std::find_if(errors.begin(), errors.end(), [](const auto& d) { return d["code"] == "JOINT_AXIS_ZERO"; });
    ASSERT_NE(axis, errors.end()) << errors.dump();
    EXPECT_EQ((*axis)["pointer"], "/nodes/3/extras/rdtf_axis") << errors.dump();
    EXPECT_EQ((*axis)["severity"], "error") << errors.dump();
    if (command == "validate") {
      EXPECT_EQ(out["passed"], false);
    }
  }
}

TEST(Cli, DensityOptionScalesMass) {
  const auto run = testing::run_command(cli() + " inspect --json --density 2000 " + fixture("arm3.gltf"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  EXPECT_NEAR(summary["links"][0]["mass"].get<double>(), 16.000000715255748, 16e-6);
}

TEST(Cli, HelpForEveryCommand) {
  for (const char* command : {"", " convert", " inspect"}) {
    const auto run = testing::run_command(cli() + command + " --help");
    EXPECT_EQ(run.exit_code, 0) << command;
    EXPECT_NE(run.out.find("Usage"), std::string::npos) << command;
  }
}

TEST(Cli, UnknownOptionIsAUsageError) {
  const auto run = testing::run_command(cli() + " convert --no-such-option x.gltf");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("no-such-option"), std::string::npos) << run.err;
  // Before a command too: the word is named (CLI11 said only "A subcommand is required").
  for (const auto& [word, kind] : {std::pair{"frob", "command"}, std::pair{"--bogus", "option"}}) {
    const auto first = testing::run_command(cli() + " " + word + " x.gltf");
    EXPECT_EQ(first.exit_code, 109) << word;
    EXPECT_NE(first.err.find("rdtf: unknown " + std::string(kind) + " '" + word + "'; the commands are convert, inspect"),
              std::string::npos)
        << first.err;
    EXPECT_TRUE(first.out.empty()) << first.out;
  }
}

// urdfdom's links own their children, so freeing its model of a long chain recursed once per link,
// inside import (its parse), the URDF export (its model) and the export's check (its parse again):
// a 20,000-link chain overflowed a 1 MiB stack (ulimit -s 1024; systemd's LimitSTACK, the threads
// of programs that embed librdtf), and 200,000 links the default 8 MiB. Each link is 0.1 m below the
// last, welded, 1 kg.
TEST(Cli, ALongChainOfLinksNeedsNoDeepStack) {
  testing::TempDir folder;
  std::string urdf = "<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n";
  constexpr int kLinks = 20000;
  for (int i = 0; i < kLinks; ++i) {
    urdf += "<link name=\"l" + std::to_string(i) +
            "\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" "
            "izz=\"0.01\"/></inertial></link>\n";
    if (i > 0) {
      urdf += "<joint name=\"j" + std::to_string(i) + "\" type=\"fixed\"><parent link=\"l" + std::to_string(i - 1) +
              "\"/><child link=\"l" + std::to_string(i) + "\"/><origin xyz=\"0 0 0.1\"/></joint>\n";
    }
  }
  testing::write_file(folder / "chain.urdf", urdf + "</robot>\n");
  const std::string small_stack = "cd '" + folder.path().string() + "' && ulimit -s 1024 && " + cli();
  const auto imported = testing::run_command(small_stack + " import chain.urdf -o chain.glb");
  ASSERT_EQ(imported.exit_code, 0) << imported.err.substr(0, 2000);
  EXPECT_NE(imported.err.find("20000 links, 19999 joints"), std::string::npos) << imported.err.substr(0, 2000);
  const auto exported = testing::run_command(small_stack + " urdf chain.glb -o out");
  ASSERT_EQ(exported.exit_code, 0) << exported.err.substr(0, 2000);
  EXPECT_TRUE(std::filesystem::is_regular_file(folder / "out" / "robot.urdf"));
}

// A file whose name starts with '-' is read as an option; the error names the file and the way
// to give it (CLI11 said only "input is required").
TEST(Cli, AFileNamedLikeAnOptionIsNamed) {
  testing::TempDir folder;
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.glb", folder / "-model.glb");
  const std::string in_folder = "cd '" + folder.path().string() + "' && " + cli();
  const auto run = testing::run_command(in_folder + " inspect -model.glb");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("rdtf: '-model.glb' was read as an option; for the file of that name write ./-model.glb"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(testing::run_command(in_folder + " inspect ./-model.glb").exit_code, 0);
  EXPECT_EQ(testing::run_command(in_folder + " inspect -- -model.glb").exit_code, 0);
}

// A number an option refuses says what it must be (CLI11's own check printed a range of 309 digits).
TEST(Cli, ANumberOutOfRangeSaysWhatItMustBe) {
  for (const auto& [value, says] : {std::pair{"0", "--density: is 0; it must be more than 0"},
                                    std::pair{"-1", "--density: is -1; it must be more than 0"},
                                    std::pair{"abc", "--density: 'abc' is not a number"}}) {
    const auto run = testing::run_command(cli() + " convert x.gltf --density " + value);
    EXPECT_EQ(run.exit_code, 105) << value;
    EXPECT_NE(run.err.find(says), std::string::npos) << run.err;
  }
}

TEST(Cli, MissingInputFileExits2) {
  const auto run = testing::run_command(cli() + " inspect /nonexistent/model.gltf");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("/nonexistent/model.gltf"), std::string::npos) << run.err;
}

// Every path below `dir`, relative, sorted: what a command left behind.
std::vector<std::string> contents(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    found.push_back(entry.path().lexically_relative(dir).string());  // not relative(): it follows links
  }
  std::sort(found.begin(), found.end());
  return found;
}

// Outputs that cannot be written are refused before anything is: a folder (its .bin used to be
// written as '.bin' before the JSON failed, exit 1), a path below a file, a .bin that is a folder,
// an output its own buffer would overwrite.
TEST(Cli, ConvertOntoUnwritablePlacesIsExitTwoAndWritesNothing) {
  testing::TempDir folder;
  std::filesystem::create_directories(folder / "out");
  std::filesystem::create_directories(folder / "binfolder/x.bin");
  testing::write_file(folder / "afile", "");
  // Links: the rename would replace the link, not write through it (`-o /dev/stdout` with stdout
  // sent to a file replaced the system's /dev/stdout link; "stdout" here is a link like it).
  testing::write_file(folder / "target.glb", "the user's");
  std::filesystem::create_symlink(folder / "target.glb", folder / "link.glb");
  std::filesystem::create_symlink("/proc/self/fd/1", folder / "stdout");
  std::filesystem::create_directories(folder / "binlink");
  std::filesystem::create_symlink(folder / "target.glb", folder / "binlink/x.bin");
  const std::vector<std::string> before = contents(folder.path());
  const std::string out = (folder / "out").string();
  const std::pair<std::string, std::string> cases[] = {
      {out + "/", "is a folder, not a file: give the file to write, e.g. " + out + "/arm3.rdtf.gltf"},
      {(folder / "new/").string(), "names a folder (it ends in '/'), not a file: give the file to write, e.g. " +
                                       (folder / "new/arm3.rdtf.gltf").string()},
      {out, "is a folder, not a file: give the file to write, e.g. " + out + "/arm3.rdtf.gltf"},
      {(folder / "afile/x.gltf").string(), (folder / "afile").string() + " is a file, not a folder"},
      // arm3.gltf's buffer goes beside the output, named after it: x.bin.
      {(folder / "binfolder/x.gltf").string(),
       "the buffer or image " + (folder / "binfolder/x.bin").string() + " is a folder"},
      {(folder / "arm3.bin").string(), "the output would be written over by its own buffer or image arm3.bin"},
      {(folder / "link.glb").string(), "the output " + (folder / "link.glb").string() + " is a symbolic link (to " +
                                           (folder / "target.glb").string() + "): rdtf writes a new file and renames it"},
      {(folder / "stdout").string(), "the output " + (folder / "stdout").string() + " is a symbolic link (to /proc/self/fd/1)"},
      {(folder / "binlink/x.gltf").string(), "the buffer or image " + (folder / "binlink/x.bin").string() +
                                                 " is a symbolic link"},
  };
  for (const auto& [output, says] : cases) {
    const auto run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" + output + "'");
    EXPECT_EQ(run.exit_code, 2) << output << "\n" << run.err;
    EXPECT_NE(run.err.find(output + ": error OUTPUT_PATH_INVALID: " + says), std::string::npos) << run.err;
    EXPECT_EQ(contents(folder.path()), before) << output;
  }
  EXPECT_EQ(testing::read_file(folder / "target.glb"), "the user's");
  EXPECT_TRUE(std::filesystem::is_symlink(folder / "stdout"));
  // "-" is standard output to Unix tools: it made files named "-" and "-.bin" in the working folder.
  for (const char* command : {" convert ", " import ", " urdf "}) {
    const std::string input = std::string(command) == " import " ? "'" + (testing::data_dir() / "robots" / "r2d2.urdf").string() + "'"
                                                                 : fixture("arm3.gltf");
    const auto run = testing::run_command("cd '" + folder.path().string() + "' && " + cli() + command + input + " -o -");
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find("-: error OUTPUT_PATH_INVALID: '-' (standard output): rdtf writes no model to standard output"),
              std::string::npos)
        << run.err;
    EXPECT_EQ(contents(folder.path()), before) << command;
  }
}

// An image the model names through a link in its own folder is read, and not written again when
// the output goes beside the model: it is no output, so its being a link is no reason to refuse.
TEST(Cli, ALinkedImageBesideTheModelIsNoOutputOfItsOwn) {
  testing::TempDir folder;
  std::filesystem::create_directories(folder / "textures");
  // A 2x2 RGBA checker.
  const std::string png(
      "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x02\x00\x00\x00\x02\x08\x06"
      "\x00\x00\x00\x72\xb6\x0d\x24\x00\x00\x00\x12\x49\x44\x41\x54\x78\x9c\x63\xf8\xcf\xc0\xf0\x1f\x04\xa0\x24"
      "\xc3\x7f\x00\x6b\xa6\x0b\xf5\xc4\xb7\x3b\xa8\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
      75);
  testing::write_file(folder / "textures/red.png", png);
  std::filesystem::create_symlink("textures/red.png", folder / "red.png");
  nlohmann::json model = nlohmann::json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  model["images"] = {{{"uri", "red.png"}}};
  model["buffers"][0]["uri"] = "arm3.bin";
  testing::write_file(folder / "arm3.gltf", model.dump());
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", folder / "arm3.bin");
  const auto run = testing::run_command(cli() + " convert '" + (folder / "arm3.gltf").string() + "' -o '" +
                                        (folder / "arm3_rdtf.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::is_symlink(folder / "red.png"));
  EXPECT_TRUE(std::filesystem::is_regular_file(folder / "arm3_rdtf.bin"));
}

// A stage folder whose writer was killed (a CI job at its timeout) is removed by the next convert
// into that folder once untouched for an hour (they stayed for ever, tens of megabytes each); a
// live writer's stays, and so does a dead pid's touched lately (a writer in another PID namespace).
TEST(Cli, ConvertRemovesTheStagesOfWritersThatAreGone) {
  testing::TempDir folder;
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ASSERT_GT(gone, 0);
  ::waitpid(gone, nullptr, 0);
  const auto stage = [&](pid_t pid) { return folder / (".rdtf-stage." + std::to_string(pid) + "-12345.tmp"); };
  const auto recent = folder / (".rdtf-stage." + std::to_string(gone) + "-67890.tmp");
  for (const auto& path : {stage(gone), stage(::getpid()), recent}) {
    std::filesystem::create_directories(path);
    testing::write_file(path / "big.glb", "part of an output");
  }
  const auto two_hours_ago = std::filesystem::file_time_type::clock::now() - std::chrono::hours(2);
  for (const auto& path : {stage(gone), stage(gone) / "big.glb", stage(::getpid()), stage(::getpid()) / "big.glb"}) {
    std::filesystem::last_write_time(path, two_hours_ago);
  }
  const auto run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" + (folder / "x.glb").string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_FALSE(std::filesystem::exists(stage(gone)));
  EXPECT_TRUE(std::filesystem::exists(stage(::getpid()) / "big.glb"));
  EXPECT_TRUE(std::filesystem::exists(recent / "big.glb"));
}

// Folders that do not exist yet are made, for .gltf and .glb alike (a .glb there failed).
TEST(Cli, ConvertCreatesTheOutputFolder) {
  testing::TempDir folder;
  for (const char* output : {"new/dir/x.glb", "other/dir/x.gltf"}) {
    const auto run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" +
                                          (folder / output).string() + "'");
    EXPECT_EQ(run.exit_code, 0) << output << "\n" << run.err;
    EXPECT_TRUE(std::filesystem::is_regular_file(folder / output)) << output;
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(folder / "other/dir/x.bin"));
}

// A write that fails takes back what it made: here the folder it created for the output, and the
// buffer it wrote first. (The buffer's name, 251 characters and ".bin", is within the 255 the
// file system allows; the output's, 251 and ".gltf", is one over.)
TEST(Cli, FailedWriteLeavesNothingBehind) {
  testing::TempDir folder;
  const std::filesystem::path output = folder / "new" / (std::string(251, 'a') + ".gltf");
  const auto run = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" + output.string() + "'");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("error WRITE_FAILED: cannot write " + (folder / "new").string() + "/aaaa"), std::string::npos)
      << run.err;
  EXPECT_TRUE(contents(folder.path()).empty());
}

// Under a file-size limit (ulimit -f, systemd's LimitFSIZE) a write fails with EFBIG, reported as
// any failed write, with nothing left behind; SIGXFSZ killed rdtf mid-write (exit 153) and left
// its stage folder. bash's ulimit -f counts 1024-byte blocks: arm3's outputs are larger.
TEST(Cli, AFileSizeLimitIsAFailedWriteNotASignal) {
  testing::TempDir folder;
  const std::filesystem::path output = folder / "out" / "arm3.rdtf.glb";
  const auto run =
      testing::run_command("ulimit -f 2; " + cli() + " convert " + fixture("arm3.gltf") + " -o '" + output.string() + "'");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("error WRITE_FAILED: cannot write " + (folder / "out").string()), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("File too large"), std::string::npos) << run.err;
  EXPECT_TRUE(contents(folder.path()).empty());
}

// What a script reads on stdout is whole or the command fails: a report that could not be written
// (a full disk; /dev/full here, or a closed stdout) was exit 0 with its JSON cut short.
TEST(Cli, AnUnwritableStdoutIsAFailure) {
  for (const char* redirect : {">/dev/full", ">&-"}) {
    SCOPED_TRACE(redirect);
    const auto run = testing::run_command(cli() + " inspect --json " + fixture("arm3.gltf") + " " + redirect);
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_NE(run.err.find("rdtf: could not write to standard output"), std::string::npos) << run.err;
  }
  // A command that prints nothing on stdout does not care where it goes.
  testing::TempDir folder;
  const auto converted = testing::run_command(cli() + " convert " + fixture("arm3.gltf") + " -o '" +
                                              (folder / "a.rdtf.glb").string() + "' >&-");
  EXPECT_EQ(converted.exit_code, 0) << converted.err;
}

// Outputs are created 0666 less the umask, as cp makes files: under umask 002 a group shares them
// as it shares the folders made for them; under 077 they stay private (they were always 0644).
TEST(Cli, OutputsFollowTheUmask) {
  for (const auto& [umask, mode] : {std::pair{"002", 0664}, std::pair{"077", 0600}, std::pair{"022", 0644}}) {
    SCOPED_TRACE(umask);
    testing::TempDir folder;
    const auto run = testing::run_command(std::string("umask ") + umask + "; " + cli() + " convert " + fixture("arm3.gltf") +
                                          " -o '" + (folder / "out" / "arm3.rdtf.gltf").string() + "'");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(folder / "out")) {
      struct stat info {};
      ASSERT_EQ(::stat(entry.path().c_str(), &info), 0);
      EXPECT_EQ(info.st_mode & 0777, static_cast<unsigned>(mode)) << entry.path();
      ++files;
    }
    EXPECT_EQ(files, 2);  // the JSON and its .bin
  }
}

// The system calls that make data durable, as strace logged them (one line each).
int sync_calls(const std::filesystem::path& log) {
  std::istringstream lines(testing::read_file(log));
  int count = 0;
  for (std::string line; std::getline(lines, line);) {
    for (const char* call : {"fsync(", "fdatasync(", "syncfs(", "sync_file_range("}) {
      if (line.find(call) != std::string::npos) ++count;
    }
  }
  return count;
}

// Without --sync an output is moved into place whole and nothing is fsynced (as cp or a compiler
// writes); with it, the GLB and then its folder are, before rdtf exits: two fsyncs. Both write
// the same bytes.
TEST(Cli, ConvertSyncsOnlyWhenAsked) {
  testing::TempDir folder;
  const auto plain = folder / "plain.glb", synced = folder / "synced.glb";
  const auto log = folder / "strace.log";
  // LeakSanitizer cannot run under ptrace (the sanitizer build of CI): leaks are not looked for in
  // the traced process alone, whatever else ASAN_OPTIONS asks.
  const std::string strace =
      "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" strace -f -qq "
      "-e trace=fsync,fdatasync,syncfs,sync_file_range -o '" + log.string() + "' ";
  auto run = testing::run_command(strace + cli() + " convert " + fixture("arm3.gltf") + " -o '" + plain.string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(sync_calls(log), 0) << testing::read_file(log);
  run = testing::run_command(strace + cli() + " convert " + fixture("arm3.gltf") + " --sync -o '" + synced.string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string calls = testing::read_file(log);
  EXPECT_EQ(std::count(calls.begin(), calls.end(), '\n'), 3) << calls;  // sync_file_range, fsync file, fsync folder
  EXPECT_EQ(sync_calls(log), 3) << calls;
  EXPECT_EQ(testing::read_file(plain), testing::read_file(synced));
  // The stage is gone either way: the folder holds the two outputs and the log.
  EXPECT_EQ(contents(folder.path()).size(), 3u);
}

}  // namespace
}  // namespace rdtf
