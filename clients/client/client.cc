#include "rdtf/client.h"

#include <unistd.h>

#include <openssl/evp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <regex>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>

#include "assembly.h"
#include "blob_fetch.h"
#include "safe_decode.h"

namespace rdtf::client {

using detail::BlobFetcher;
using detail::BlobStore;
using detail::RevisionParts;

std::string sha256_hex(const void* data, std::size_t size) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(data, size, digest, &length, EVP_sha256(), nullptr);
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 15];
  }
  return out;
}

std::string check_relative_path(const std::string& path) {
  if (path.empty()) return "empty path";
  if (path.size() > 4096) return "path longer than 4096 bytes";
  if (path.front() == '/') return "absolute path '" + lcm_safe::printable(path, 120) + "'";
  for (const unsigned char c : path) {
    if (c < 0x20 || c == 0x7f || c == '\\') return "control character or backslash in '" + lcm_safe::printable(path, 120) + "'";
  }
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    const std::string_view part(path.data() + start, end - start);
    if (part.empty() || part == "." || part == "..") {
      return "'" + lcm_safe::printable(path, 120) + "' has an empty, '.' or '..' part";
    }
    if (part.size() > 255) return "a part of '" + lcm_safe::printable(path, 120) + "' longer than 255 bytes";
    start = end + 1;
  }
  return "";
}

const std::string* Snapshot::file(const std::string& path) const {
  for (const auto& f : manifest) {
    if (f.path != path) continue;
    const auto it = blobs.find(f.sha256);
    return it == blobs.end() ? nullptr : it->second.get();
  }
  return nullptr;
}

namespace {

// Revision key within a model.
using Key = std::pair<std::int64_t, std::string>;

struct Pending {
  Pending(const std::string& model_id, const Key& key, Clock::time_point now)
      : parts(model_id, key.first, key.second), first_seen(now) {}
  RevisionParts parts;
  Clock::time_point first_seen;
  std::optional<Snapshot> assembled;  // every part here; waiting for `missing` blobs
  std::set<std::string> missing;
};

struct ModelState {
  std::shared_ptr<const Snapshot> current;
  std::uint64_t epoch = 0;      // The rdtfd instance (Impl::daemon_epoch) that described `current`,
  bool known_daemon = false;    // when a STATUS had named one by then.
  int unlisted = 0;  // STATUS messages in a row that did not list it as live
  std::map<Key, Pending> pending;
  Clock::time_point next_request{};
  Clock::duration backoff{};
};

std::string regex_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (std::string_view("\\.^$|?*+()[]{}").find(c) != std::string_view::npos) out += '\\';
    out += c;
  }
  return out;
}

std::string default_requester() {
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) != 0) host[0] = '\0';
  return "rdtf_client " + std::string(host) + " " + std::to_string(::getpid());
}

template <typename Message>
std::vector<std::uint8_t> encode(const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::string waiter_of(const std::string& model_id, const Key& key) {
  return model_id + "\n" + std::to_string(key.first) + "\n" + key.second;
}

}  // namespace

struct Client::State {
  State(Publish publish_in, Options options_in, Callbacks callbacks_in)
      : options(std::move(options_in)),
        callbacks(std::move(callbacks_in)),
        publish(std::move(publish_in)),
        store(options.limits.max_store_bytes),
        fetcher(
            options, store,
            [this](const rdtf::blob_request_t& request) {
              rdtf::blob_request_t r = request;
              r.utime = now_utime();
              r.requester = options.requester;
              publish(options.prefix + "/BLOB_REQUEST", encode(r));
            },
            [this](const std::string& sha, const std::string& problem) { on_blob_done(sha, problem); }, stats) {
    if (options.requester.empty()) options.requester = default_requester();
    if (options.model.empty() && !options.pattern.empty()) pattern.emplace(options.pattern, std::regex::extended);
    start_backoff = options.retry_initial;
  }

  static std::int64_t now_utime() {
    using namespace std::chrono;
    return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
  }

  void drop(const std::string& channel, const std::string& why) {
    ++stats.dropped;
    if (callbacks.on_drop) {
      callbacks.on_drop(channel, why);
    } else if (auto line = drops.drop(channel, why, Clock::now())) {
      std::cerr << "rdtf_client: " << *line << "\n";
    }
  }
  void problem(const std::string& model_id, const std::string& text) {
    if (callbacks.on_problem) {
      callbacks.on_problem(model_id, text);
    } else {
      std::cerr << "rdtf_client: " << lcm_safe::printable(model_id, 80) << ": " << lcm_safe::printable(text) << "\n";
    }
  }

  void request(const std::string& model_id) {
    if (!options.send_requests) return;
    rdtf::request_t r;
    r.utime = now_utime();
    r.model_id = model_id;
    r.requester = options.requester;
    publish(options.prefix + "/REQUEST", encode(r));
    ++stats.requests_sent;
  }

  bool follows(const std::string& model_id) const {
    if (!options.model.empty()) return model_id == options.model;
    if (pattern) return std::regex_match(model_id, *pattern);
    return true;
  }

  void note_seen(const std::string& model_id) {
    if (seen.size() < options.limits.max_models || seen.count(model_id)) seen.insert(model_id);
  }

  template <typename Message>
  std::optional<Message> decode(const std::string& channel, const void* data, std::size_t size) {
    std::string why;
    auto message = lcm_safe::decode<Message>(data, size, why);
    if (!message) drop(channel, why);
    return message;
  }

  void on_datagram(const std::string& channel, const void* data, std::size_t size, Clock::time_point now) {
    ++stats.datagrams;
    stats.bytes += size;
    const std::string head = options.prefix + "/";
    if (channel.rfind(head, 0) != 0) return;
    const std::string rest = channel.substr(head.size());
    if (rest == "STATUS") {
      if (auto s = decode<rdtf::status_t>(channel, data, size)) {
        for (const auto& id : s->model_ids) note_seen(id);
        followed_live = std::any_of(s->model_ids.begin(), s->model_ids.end(),
                                    [&](const std::string& id) { return follows(id); });
        forget_models_not_live(*s);
        note_daemon(*s);
      }
      return;
    }
    if (options.blobs != Blobs::kNone && rest == "BLOB") {
      if (auto c = decode<rdtf::blob_chunk_t>(channel, data, size)) {
        if (const std::string why = fetcher.on_chunk(*c, now); !why.empty()) drop(channel, why);
      }
      return;
    }
    if (options.blobs != Blobs::kNone && rest == "BLOB_UNAVAILABLE") {
      if (auto u = decode<rdtf::blob_unavailable_t>(channel, data, size)) {
        std::set<std::string> named;
        for (const auto& [waiter, text] : fetcher.on_unavailable(*u, now)) {
          const std::string model_id = waiter.substr(0, waiter.find('\n'));
          problem(model_id, text);
          named.insert(model_id);
        }
        for (const auto& model_id : named) request(model_id);
      }
      return;
    }
    const auto slash = rest.rfind('/');
    if (slash == std::string::npos || slash == 0) return;
    const std::string model_id = rest.substr(0, slash);
    const std::string kind = rest.substr(slash + 1);
    if (!follows(model_id)) return;
    on_model_datagram(channel, model_id, kind, data, size, now);
  }

  // The message's own model_id must be its channel's.
  template <typename Message>
  std::optional<Message> decode_for(const std::string& channel, const std::string& model_id, const void* data,
                                    std::size_t size) {
    auto message = decode<Message>(channel, data, size);
    if (message && message->model_id != model_id) {
      drop(channel, "model_id '" + lcm_safe::printable(message->model_id, 80) + "' is not the channel's");
      return std::nullopt;
    }
    return message;
  }

  void on_model_datagram(const std::string& channel, const std::string& model_id, const std::string& kind,
                         const void* data, std::size_t size, Clock::time_point now) {
    if (kind == "JOINT_STATE" || kind == "LINK_STATE") {
      if (!options.states) return;
      const auto model = models.find(model_id);
      if (model == models.end() || !model->second.current) return;
      const Snapshot& current = *model->second.current;
      if (kind == "JOINT_STATE") {
        auto s = decode_for<rdtf::joint_state_t>(channel, model_id, data, size);
        if (s && s->revision == current.revision() && s->content_hash == current.content_hash() &&
            callbacks.on_joint_state) {
          callbacks.on_joint_state(current, *s);
        }
      } else {
        auto s = decode_for<rdtf::link_state_t>(channel, model_id, data, size);
        if (s && s->revision == current.revision() && s->content_hash == current.content_hash() &&
            callbacks.on_link_state) {
          callbacks.on_link_state(current, *s);
        }
      }
      return;
    }
    if (kind == "ERROR") {
      note_seen(model_id);
      if (auto e = decode_for<rdtf::model_error_t>(channel, model_id, data, size); e && callbacks.on_error) {
        callbacks.on_error(*e);
      }
      return;
    }
    if (kind == "SAVING") {
      if (auto saving = decode_for<rdtf::model_saving_t>(channel, model_id, data, size); saving && callbacks.on_saving) {
        callbacks.on_saving(*saving);
      }
      return;
    }
    if (kind == "REMOVED") {
      if (auto r = decode_for<rdtf::model_removed_t>(channel, model_id, data, size)) {
        forget(model_id);
        seen.erase(model_id);
        if (callbacks.on_removed) callbacks.on_removed(*r);
      }
      return;
    }
    std::string why;
    std::optional<Key> key;
    auto with_parts = [&](std::int64_t revision, const std::string& hash, auto&& add) {
      key = Key{revision, hash};
      Pending* pending = pending_of(channel, model_id, *key, now);
      if (pending == nullptr || pending->assembled) return;
      if (pending_bytes + static_cast<std::int64_t>(size) > options.limits.max_pending_bytes) {
        why = "incomplete revisions hold max_pending_bytes (" + std::to_string(options.limits.max_pending_bytes) + ")";
        return;
      }
      const std::int64_t before = pending->parts.bytes();
      why = add(pending->parts);
      pending_bytes += pending->parts.bytes() - before;
    };
    const Limits& limits = options.limits;
    if (kind == "DESCRIPTION") {
      auto d = decode_for<rdtf::description_t>(channel, model_id, data, size);
      if (!d) return;
      note_seen(model_id);
      with_parts(d->revision, d->content_hash, [&](RevisionParts& p) { return p.add_description(*d, limits); });
      if (why.empty()) drop_older(model_id, d->revision);
    } else if (kind == "DESCRIPTION_CHUNK" || kind == "URDF_CHUNK") {
      auto c = decode_for<rdtf::description_chunk_t>(channel, model_id, data, size);
      if (!c) return;
      const bool json = kind == "DESCRIPTION_CHUNK";
      with_parts(c->revision, c->content_hash, [&](RevisionParts& p) {
        return json ? p.add_json_chunk(*c, limits) : p.add_urdf_chunk(*c, limits);
      });
    } else if (kind == "INERTIA") {
      auto t = decode_for<rdtf::inertia_table_t>(channel, model_id, data, size);
      if (!t) return;
      with_parts(t->revision, t->content_hash, [&](RevisionParts& p) { return p.add_inertia(*t, limits); });
    } else if (kind == "MANIFEST") {
      auto m = decode_for<rdtf::manifest_t>(channel, model_id, data, size);
      if (!m) return;
      with_parts(m->revision, m->content_hash, [&](RevisionParts& p) { return p.add_manifest(*m, limits); });
    } else if (kind == "VALIDATION") {
      auto v = decode_for<rdtf::validation_report_t>(channel, model_id, data, size);
      if (!v) return;
      with_parts(v->revision, v->content_hash, [&](RevisionParts& p) { return p.add_validation(*v); });
    } else {
      return;
    }
    if (!why.empty()) drop(channel, why);
    if (key) try_complete(channel, model_id, *key, now);
  }

  // The parts of (model, key), made if new; nullptr when it is the current snapshot's or no
  // room is left.
  Pending* pending_of(const std::string& channel, const std::string& model_id, const Key& key, Clock::time_point now) {
    auto model = models.find(model_id);
    if (model == models.end()) {
      if (models.size() >= options.limits.max_models) {
        drop(channel, "more than max_models (" + std::to_string(options.limits.max_models) + ") models");
        return nullptr;
      }
      model = models.emplace(model_id, ModelState{}).first;
      model->second.backoff = options.retry_initial;
    }
    ModelState& m = model->second;
    if (m.current && m.current->revision() == key.first && m.current->content_hash() == key.second) return nullptr;
    if (key.first <= 0 || !detail::is_sha256_hex(key.second)) {
      drop(channel, "revision " + std::to_string(key.first) + " or content_hash not valid");
      return nullptr;
    }
    auto it = m.pending.find(key);
    if (it != m.pending.end()) return &it->second;
    if (m.pending.size() >= options.limits.max_pending_revisions) {
      auto oldest = m.pending.begin();
      for (auto p = m.pending.begin(); p != m.pending.end(); ++p) {
        if (p->second.first_seen < oldest->second.first_seen) oldest = p;
      }
      fetcher.release(waiter_of(model_id, oldest->first));
      pending_bytes -= oldest->second.parts.bytes();
      m.pending.erase(oldest);
    }
    return &m.pending.emplace(key, Pending(model_id, key, now)).first->second;
  }

  // A newer revision was described: incomplete older ones will never be published again.
  void drop_older(const std::string& model_id, std::int64_t revision) {
    auto& m = models[model_id];
    for (auto it = m.pending.begin(); it != m.pending.end();) {
      if (it->first.first < revision) {
        fetcher.release(waiter_of(model_id, it->first));
        pending_bytes -= it->second.parts.bytes();
        it = m.pending.erase(it);
      } else {
        ++it;
      }
    }
  }

  // A model rdtfd no longer lists as live is gone as if REMOVED had come: one deleted while
  // rdtfd was down never gets a REMOVED, and stayed "live" here and in every viewer. Only from a
  // STATUS with nothing pending (a restarted rdtfd lists a model once its first conversion is
  // done, which may take seconds), and after two in a row, so that one sent as a revision went
  // out cannot drop it.
  void forget_models_not_live(const rdtf::status_t& status) {
    if (status.pending != 0) return;
    const std::set<std::string> live(status.model_ids.begin(), status.model_ids.end());
    std::vector<rdtf::model_removed_t> gone;
    for (auto& [model_id, m] : models) {
      if (!m.current || live.count(model_id) != 0) {
        m.unlisted = 0;
        continue;
      }
      if (++m.unlisted < 2) continue;
      rdtf::model_removed_t removed;
      removed.utime = status.utime;
      removed.model_id = model_id;
      removed.source_path = "";
      removed.last_revision = m.current->revision();
      gone.push_back(std::move(removed));
    }
    for (const auto& removed : gone) {
      forget(removed.model_id);
      seen.erase(removed.model_id);
      if (callbacks.on_removed) callbacks.on_removed(removed);
    }
  }

  void forget(const std::string& model_id) {
    const auto model = models.find(model_id);
    if (model == models.end()) return;
    for (const auto& [key, pending] : model->second.pending) {
      fetcher.release(waiter_of(model_id, key));
      pending_bytes -= pending.parts.bytes();
    }
    models.erase(model);
  }

  void try_complete(const std::string& channel, const std::string& model_id, const Key& key, Clock::time_point now) {
    auto model = models.find(model_id);
    if (model == models.end()) return;
    auto it = model->second.pending.find(key);
    if (it == model->second.pending.end() || it->second.assembled) return;
    Pending& p = it->second;
    std::string why;
    const std::int64_t before = p.parts.bytes();
    auto snapshot = p.parts.assemble(options.blobs != Blobs::kNone, why);
    pending_bytes += p.parts.bytes() - before;  // A part that failed its check was cleared.
    if (!why.empty()) drop(channel, why);
    if (!snapshot) return;
    if (options.blobs == Blobs::kAll) {
      for (const auto& file : snapshot->manifest) {
        if (snapshot->blobs.count(file.sha256)) continue;
        if (!options.blob_roles.empty() && !options.blob_roles.count(file.role)) continue;
        if (auto bytes = store.find(file.sha256)) {
          snapshot->blobs[file.sha256] = std::move(bytes);
        } else {
          p.missing.insert(file.sha256);
          fetcher.want(file.sha256, file.size, waiter_of(model_id, key), now);
        }
      }
    }
    p.assembled = std::move(snapshot);
    if (p.missing.empty()) deliver_or_hold(model_id, key);
  }

  // Revisions only grow while one rdtfd serves a model. A complete revision that is not newer than
  // the one held (lower, or the same number with other content) comes from a replayed log or a
  // stray publisher while that rdtfd still serves the newer one: taking it would stop a controller
  // commanding the live revision (rdtfd rejects every command for another) until the next
  // republication. It is held until a STATUS shows another rdtfd started since (a restart without
  // its state folder numbers models from 1 again, docs/lcm.md), and then taken.
  // Before any STATUS (a client's first second) nothing tells one rdtfd from another, and the
  // revision described last is taken as before: a restart then must not leave the model held.
  void deliver_or_hold(const std::string& model_id, const Key& key) {
    ModelState& m = models[model_id];
    if (m.current && daemon && m.known_daemon && key.first <= m.current->revision() && m.epoch == daemon_epoch) {
      problem(model_id, "revision " + std::to_string(key.first) + " is not newer than revision " +
                            std::to_string(m.current->revision()) +
                            ", which the same rdtfd described (a replayed log?): held until a restarted rdtfd "
                            "describes it");
      return;
    }
    deliver(model_id, key);
  }

  // STATUS names the rdtfd that sends it: its pid and its start (utime - uptime). Another pid, or a
  // later start, is a restarted rdtfd; an earlier start is an earlier run's STATUS played back from
  // a log, and no news of the live one.
  void note_daemon(const rdtf::status_t& status) {
    if (!std::isfinite(status.uptime) || status.uptime < 0 || status.uptime > 1e10) return;
    const std::int64_t start = status.utime - static_cast<std::int64_t>(status.uptime * 1e6);
    constexpr std::int64_t kSlack = 1'000'000;  // us: utime and uptime are read at slightly different times
    if (daemon && status.pid == daemon->first && std::llabs(start - daemon->second) < kSlack) return;
    if (daemon && start < daemon->second - kSlack) return;
    const bool restarted = daemon.has_value();
    daemon = std::make_pair(status.pid, start);
    if (!restarted) return;
    ++daemon_epoch;
    // Revisions held for being lower: the newest complete one of each model is now the model's.
    for (auto& [model_id, m] : models) {
      const Key* held = nullptr;
      for (const auto& [key, p] : m.pending) {
        if (p.assembled && p.missing.empty() && (!held || key.first >= held->first)) held = &key;
      }
      if (held) deliver(model_id, Key(*held));
    }
  }

  void deliver(const std::string& model_id, const Key& key) {
    ModelState& m = models[model_id];
    auto it = m.pending.find(key);
    auto snapshot = std::make_shared<const Snapshot>(std::move(*it->second.assembled));
    pending_bytes -= it->second.parts.bytes();
    m.pending.erase(it);
    drop_older(model_id, key.first);
    m.current = snapshot;
    m.epoch = daemon_epoch;
    m.known_daemon = daemon.has_value();
    m.backoff = options.retry_initial;
    ++stats.revisions;
    if (callbacks.on_revision) callbacks.on_revision(snapshot);
  }

  void on_blob_done(const std::string& sha, const std::string& failure) {
    std::vector<std::pair<std::string, Key>> ready;
    std::vector<std::pair<std::string, Key>> failed;
    for (auto& [model_id, m] : models) {
      for (auto& [key, p] : m.pending) {
        if (!p.assembled || !p.missing.count(sha)) continue;
        if (!failure.empty()) {
          failed.emplace_back(model_id, key);
          continue;
        }
        p.assembled->blobs[sha] = fetcher.just_completed(sha);
        p.missing.erase(sha);
        if (p.missing.empty()) ready.emplace_back(model_id, key);
      }
    }
    for (const auto& [model_id, key] : failed) {
      problem(model_id, failure);
      fetcher.release(waiter_of(model_id, key));
      auto& pending = models[model_id].pending;
      if (const auto it = pending.find(key); it != pending.end()) {
        pending_bytes -= it->second.parts.bytes();
        pending.erase(it);
      }
    }
    for (const auto& [model_id, key] : ready) {
      if (models[model_id].pending.count(key)) deliver_or_hold(model_id, key);
    }
  }

  void tick(Clock::time_point now) {
    // The end of a burst of drops, logged once its period is over (no on_drop: that callback
    // hears every drop itself).
    if (!callbacks.on_drop) {
      if (auto line = drops.flush(now)) std::cerr << "rdtf_client: " << *line << "\n";
    }
    // Blobs the caller stopped holding since (an older snapshot dropped) go now if over capacity,
    // not only when the next blob arrives.
    store.trim();
    // Until the first description of a followed model, ask again with back-off: the first
    // answer may have been lost, or rdtfd started after this client.
    // Not once a STATUS has listed no live model this client follows: rdtfd publishes each when
    // it goes live, and asked meanwhile it only republishes refusals.
    if (!described_any() && followed_live.value_or(true) && now >= next_start_request) {
      request(options.model);
      next_start_request = now + start_backoff;
      start_backoff = std::min<Clock::duration>(start_backoff * 2, options.retry_max);
    }
    // A revision whose parts stay incomplete: ask for the model's publication again.
    for (auto& [model_id, m] : models) {
      bool stalled = false;
      for (const auto& [key, p] : m.pending) {
        stalled |= !p.assembled && !p.parts.refused_only() && now - p.first_seen >= m.backoff;
      }
      if (stalled && now >= m.next_request) {
        request(model_id);
        m.next_request = now + m.backoff;
        m.backoff = std::min<Clock::duration>(m.backoff * 2, options.retry_max);
      }
    }
    fetcher.tick(now);
  }

  bool described_any() const {
    for (const auto& [model_id, m] : models) {
      if (m.current) return true;
      for (const auto& [key, p] : m.pending) {
        if (p.parts.has_description()) return true;
      }
    }
    return false;
  }

  Options options;
  Callbacks callbacks;
  Publish publish;
  Stats stats;
  lcm_safe::DropCounter drops;
  std::optional<std::regex> pattern;
  std::map<std::string, ModelState> models;
  std::set<std::string> seen;
  BlobStore store;
  BlobFetcher fetcher;
  Clock::time_point next_start_request{};
  std::optional<bool> followed_live;  // Whether rdtfd's latest STATUS listed a followed model.
  std::optional<std::pair<std::int32_t, std::int64_t>> daemon;  // pid, start (us) of the rdtfd heard
  std::uint64_t daemon_epoch = 0;  // How many times another rdtfd was heard since the first
  Clock::duration start_backoff{};
  std::int64_t pending_bytes = 0;  // chunk bytes held by incomplete revisions of every model
};

namespace {

void on_lcm(const lcm::ReceiveBuffer* buffer, const std::string& channel, Client* client) {
  // No exception may unwind through liblcm's C frames.
  try {
    client->on_datagram(channel, buffer->data, buffer->data_size, Clock::now());
  } catch (const std::exception& e) {
    std::cerr << "rdtf_client: handler failed on " << lcm_safe::printable(channel, 80) << ": " << e.what() << "\n";
  } catch (...) {
    std::cerr << "rdtf_client: handler failed on " << lcm_safe::printable(channel, 80) << "\n";
  }
}

}  // namespace

Client::Client(lcm::LCM& lcm, Options options, Callbacks callbacks)
    : Client(
          [&lcm](const std::string& channel, const std::vector<std::uint8_t>& bytes) {
            lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
          },
          std::move(options), std::move(callbacks)) {
  lcm_ = &lcm;
  for (const auto& channel : channels()) {
    auto* subscription = lcm.subscribeFunction(channel, &on_lcm, this);
    // Blob chunks come in bursts; a queue of 256 datagrams (at most 16 MiB) rides out a caller
    // that dispatches late. What overflows is asked for again.
    subscription->setQueueCapacity(256);
    subscriptions_.push_back(subscription);
  }
  tick();  // The request that lets a late joiner start at once.
}

Client::Client(Publish publish, Options options, Callbacks callbacks)
    : state_(std::make_unique<State>(std::move(publish), std::move(options), std::move(callbacks))) {}

Client::~Client() {
  if (lcm_ != nullptr) {
    for (auto* subscription : subscriptions_) lcm_->unsubscribe(subscription);
  }
}

void Client::tick(Clock::time_point now) { state_->tick(now); }

void Client::on_datagram(const std::string& channel, const void* data, std::size_t size, Clock::time_point now) {
  state_->on_datagram(channel, data, size, now);
}

std::shared_ptr<const Snapshot> Client::snapshot(const std::string& model_id) const {
  const auto it = state_->models.find(model_id);
  return it == state_->models.end() ? nullptr : it->second.current;
}

std::string Client::waiting_for(const std::string& model_id) const {
  const auto it = state_->models.find(model_id);
  if (it == state_->models.end() || it->second.pending.empty()) return "";
  const Pending* newest = nullptr;
  for (const auto& [key, pending] : it->second.pending) {
    if (newest == nullptr || pending.parts.revision() >= newest->parts.revision()) newest = &pending;
  }
  const std::string revision = "revision " + std::to_string(newest->parts.revision()) + ": ";
  if (!newest->assembled) return revision + newest->parts.missing(state_->options.blobs != Blobs::kNone);
  std::string files;
  for (const rdtf::file_t& file : newest->assembled->manifest) {
    if (newest->missing.count(file.sha256) == 0) continue;
    files += (files.empty() ? "" : "; ") + file.path + " (" + file.sha256.substr(0, 12) +
             "): " + state_->fetcher.progress(file.sha256);
  }
  return revision + std::to_string(newest->missing.size()) + " of " +
         std::to_string(newest->assembled->manifest.size()) + " files not complete: " + files;
}

std::set<std::string> Client::models_seen() const { return state_->seen; }

std::vector<std::string> Client::channels() const {
  const Options& o = state_->options;
  const std::string prefix = regex_escape(o.prefix);
  const std::string models = !o.model.empty() ? regex_escape(o.model) : !o.pattern.empty() ? "(" + o.pattern + ")" : ".+";
  std::string kinds = "DESCRIPTION|DESCRIPTION_CHUNK|URDF_CHUNK|INERTIA|MANIFEST|VALIDATION|ERROR|REMOVED|SAVING";
  if (o.states) kinds += "|JOINT_STATE|LINK_STATE";
  std::vector<std::string> out = {prefix + "/" + models + "/(" + kinds + ")", prefix + "/STATUS"};
  if (o.blobs != Blobs::kNone) {
    out.push_back(prefix + "/BLOB");
    out.push_back(prefix + "/BLOB_UNAVAILABLE");
  }
  return out;
}

Stats Client::stats() const { return state_->stats; }

}  // namespace rdtf::client
