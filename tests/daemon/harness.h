// Harness for the rdtfd integration tests (tests/daemon/*_itest.cc, program rdtf_itests): the
// library rdtf_itest_harness (tests/support/harness/*.cc, shared with bench/), included whole.
//
// How these tests run
// -------------------
// - ctest runs every test case of rdtf_itests as its own process inside a fresh network namespace
//   (tests/support/in_netns.sh: `unshare -n`, loopback up with multicast, a route for
//   224.0.0.0/4). LCM's default URL (udpm://239.255.76.67:7667?ttl=0) therefore works, no traffic
//   leaves the machine, and parallel test cases never hear each other. Run them with
//     ctest --test-dir build -L integration --output-on-failure
//   or one case by hand:
//     tests/support/in_netns.sh build/tests/rdtf_itests --gtest_filter='DaemonWatch.Delete*'
//   (running rdtf_itests outside a namespace would multicast on the host's network: don't).
// - Each test starts the real `rdtfd` (RDTFD_PATH) as a child process on a temporary watched
//   folder and a temporary output folder, with a config file written by the test
//   (status_period_ms 100 so that tests can synchronise on the heartbeat; "validate": false and
//   "simulate": false unless a test is about them: the ODE check adds a VALIDATION message per
//   revision and the live simulation a JOINT_STATE stream, both covered by the dynamics tests
//   and by DaemonLife.DefaultsValidateEveryRevisionBeforePublishingIt) and the command line
//   options --watch, --output, --settle-ms and --republish-ms (0 unless the test is about
//   republishing). rdtfd's stdout and stderr (its log) go to a file; on a failure the test prints
//   it.
// - A Subscriber (an lcm::LCM on the default URL, its own thread) records every message on
//   `RDTF/.*` with its channel, its bytes and its decoding by clients/echo/message_json.h. It is
//   created before the daemon starts, so nothing is missed.
// - Tests synchronise on messages, never on fixed sleeps: wait_for() checks the recorded messages
//   on each arrival (and every 5 ms) until a condition holds or a deadline of a few seconds passes. "Nothing else happened" is
//   checked after the daemon reports quiet: wait_idle() waits for STATUS heartbeats (published
//   after everything queued before them) showing no pending model and unchanged counters.
//   Sleeps appear only where a test deliberately spaces writes (partial writes, a slow writer).
// - Expected content comes from the files the test wrote: content_hash is computed here the way
//   the daemon does (SHA-256 over each file's 64-bit length and bytes: the model, then every file
//   it refers to, in the order of its buffers/images); masses come from `rdtf inspect --json`
//   (RDTF_CLI_PATH) run on the same file.
// - Models are either fixtures (tests/data/blender) or generated here (box_model()): chains of
//   boxes whose masses are known in closed form, with an external .bin or an embedded buffer;
//   many_parts_model() gives a small file whose RDTF JSON needs several DESCRIPTION_CHUNKs.
// - The inotify overflow test holds rdtfd with SIGSTOP while it makes 20,000 events (more than
//   the kernel's max_queued_events, 16384, which is global and left alone), then SIGCONT.
// - Other programs (lcm-logger, lcm-logplayer, rdtf-echo) run as ChildProcess, their output to a
//   file. Every child is killed by its destructor if a test ends early; temporary folders go too.
// - Budget: each case has deadlines of a few seconds; the whole label runs in about 30 s.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "support/harness/basics.h"
#include "support/harness/files.h"
#include "support/harness/hashes.h"
#include "support/harness/messages.h"
#include "support/harness/models.h"
#include "support/harness/process.h"
#include "support/harness/session.h"
#include "support/harness/subscriber.h"
