// Merging shards (`city3d merge`): the outputs of `reconstruct --shard K/N` runs made into the outputs
// of one run, from their journals and models alone.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "batch/advice.hpp"
#include "batch/finalise.hpp"
#include "batch/journal.hpp"
#include "city3d/batch.hpp"
#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "files/atomic_file.hpp"
#include "files/output_folder.hpp"

namespace city3d {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// What differs between the runs of two shard folders, as their run.json files state them: the city3d
// version, the inputs and the parameters, each key that differs with both values; empty when the
// files cannot tell (what differs is then the block size or the shard count, or the inputs' contents).
std::string what_differs(const std::string& a, const std::string& b, const detail::JournalHeader& ha,
                         const detail::JournalHeader& hb) {
  const auto read = [](const std::string& dir) {
    std::ifstream in(fs::path(dir) / "run.json", std::ios::binary);
    return nlohmann::json::parse(in, nullptr, false);
  };
  const nlohmann::json x = read(a), y = read(b);
  std::string out;
  const auto add = [&out](const std::string& what, const std::string& in_a, const std::string& in_b) {
    out += (out.empty() ? "" : "; ") + what + ": " + in_a + " against " + in_b;
  };
  if (ha.shards != hb.shards) add("shard count", std::to_string(ha.shards), std::to_string(hb.shards));
  if (ha.block_size != hb.block_size)
    add("--block-size", nlohmann::json(ha.block_size).dump(), nlohmann::json(hb.block_size).dump());
  if (!x.is_object() || !y.is_object()) return out;
  if (x.value("city3d", "") != y.value("city3d", ""))
    add("city3d version", x.value("city3d", ""), y.value("city3d", ""));
  for (const char* section : {"inputs", "parameters"}) {
    const nlohmann::json empty = nlohmann::json::object();
    const nlohmann::json& p = x.contains(section) ? x.at(section) : empty;
    const nlohmann::json& q = y.contains(section) ? y.at(section) : empty;
    if (!p.is_object() || !q.is_object()) continue;
    std::vector<std::string> keys;
    for (const auto& [k, v] : p.items()) keys.push_back(k);
    for (const auto& [k, v] : q.items()) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (const std::string& k : keys) {
      const std::string in_a = p.contains(k) ? p.at(k).dump() : "none",
                        in_b = q.contains(k) ? q.at(k).dump() : "none";
      if (in_a != in_b) add(std::string(section == std::string("inputs") ? "input " : "--") + k, in_a, in_b);
    }
  }
  return out;
}

}  // namespace

BatchSummary merge_shards(const MergeOptions& options) {
  const auto start = Clock::now();
  if (options.shard_dirs.empty()) throw ConfigError("merge: no shard folder given");
  struct Shard {
    std::string dir;
    std::unique_ptr<detail::JournalReader> journal;
    detail::RunManifest manifest;
  };
  std::vector<Shard> shards;
  std::error_code ec;
  const fs::path out_canonical = fs::weakly_canonical(options.output_dir, ec);
  for (const std::string& dir : options.shard_dirs) {
    Shard s;
    s.dir = dir;
    if (fs::weakly_canonical(dir, ec) == out_canonical)
      throw ConfigError("merge: the output folder " + options.output_dir + " is one of the shard folders");
    const fs::path journal = fs::path(dir) / "resume.journal";
    if (!fs::exists(journal, ec))
      throw IoError("merge: " + dir + " holds no resume.journal: not the output folder of `city3d reconstruct --shard`");
    s.journal = std::make_unique<detail::JournalReader>(journal.string());
    if (!s.journal->header_ok())
      throw IoError("merge: the journal of " + dir + " is damaged or from another city3d version; run that shard again");
    const detail::JournalHeader& h = s.journal->header();
    const std::string name = "shard " + std::to_string(h.shard) + "/" + std::to_string(h.shards) + " (" + dir + ")";
    if (h.shards == 0) throw ConfigError("merge: " + dir + " is the output of a whole run, not of a shard (--shard K/N)");
    if (!s.journal->damaged().empty())
      throw IoError("merge: " + name + " is damaged (line " + std::to_string(s.journal->damaged().front().first) +
                    " of its journal); run that shard again, it recomputes what is damaged");
    const bool complete = detail::read_manifest(dir, s.manifest) && s.manifest.header.fingerprint == h.fingerprint &&
                          s.manifest.header.shard == h.shard && s.manifest.header.shards == h.shards &&
                          s.manifest.records == h.expected && s.journal->records().size() == h.expected;
    if (!complete)
      throw IoError("merge: " + name + " is incomplete: " + std::to_string(s.journal->records().size()) + " of " +
                    std::to_string(h.expected) + " buildings finished" +
                    (fs::exists(fs::path(dir) / "run.json", ec) ? "" : ", no run.json") +
                    "; run it again (it resumes where it stopped)");
    shards.push_back(std::move(s));
  }
  const detail::JournalHeader& first = shards.front().journal->header();
  std::vector<const Shard*> by_number(static_cast<std::size_t>(first.shards) + 1, nullptr);
  for (const Shard& s : shards) {
    const detail::JournalHeader& h = s.journal->header();
    detail::JournalHeader as_first = h;
    as_first.shard = first.shard;
    as_first.expected = first.expected;
    if (!as_first.same_run(first)) {
      const std::string differs = what_differs(shards.front().dir, s.dir, first, h);
      throw ConfigError("merge: " + shards.front().dir + " and " + s.dir + " are shards of different runs (" +
                        (differs.empty() ? "inputs, parameters, block size or shard count differ" : differs) +
                        ")");
    }
    if (by_number[static_cast<std::size_t>(h.shard)])
      throw ConfigError("merge: shard " + std::to_string(h.shard) + "/" + std::to_string(h.shards) + " given twice: " +
                        by_number[static_cast<std::size_t>(h.shard)]->dir + " and " + s.dir);
    by_number[static_cast<std::size_t>(h.shard)] = &s;
  }
  for (int k = 1; k <= first.shards; ++k)
    if (!by_number[static_cast<std::size_t>(k)])
      throw ConfigError("merge: shard " + std::to_string(k) + "/" + std::to_string(first.shards) +
                        " is missing (give the folders of all " + std::to_string(first.shards) + " shards)");

  const detail::RunLayout& layout = first.layout;
  std::vector<detail::RecordInJournal> sources;
  for (const Shard& s : shards)
    for (const detail::RecordRef& ref : s.journal->records()) sources.push_back({s.journal.get(), &ref});
  std::sort(sources.begin(), sources.end(),
            [](const detail::RecordInJournal& a, const detail::RecordInJournal& b) {
              return a.ref->index < b.ref->index;
            });
  for (std::size_t i = 0; i < sources.size(); ++i)
    if (sources[i].ref->index != i || i >= layout.records)
      throw IoError("merge: record " + std::to_string(i) + " is " +
                    (sources[i].ref->index > i ? "in no shard" : "in two shards") + " (" +
                    sources[i].journal->path() + ")");
  if (sources.size() != layout.records)
    throw IoError("merge: the shards hold " + std::to_string(sources.size()) + " of " +
                  std::to_string(layout.records) + " buildings");

  detail::OutputFolder folder(options.output_dir, detail::run_level_files(layout, detail::FinaliseScope::whole_run));
  detail::JournalHeader whole = first;
  whole.shard = whole.shards = 0;
  whole.block_size = 0.0;
  whole.expected = layout.records;
  {
    // What an earlier run left in the output folder's journal (other inputs or parameters).
    detail::Journal previous(options.output_dir, whole, false);
    // Those this merge writes again, the same bytes under the same name, stay (a merge repeated).
    std::set<std::pair<std::string, std::string>> writing;
    for (const detail::RecordInJournal& source : sources)
      if (!source.ref->model_file.empty()) writing.emplace(source.ref->model_file, source.ref->model_hash);
    std::vector<std::pair<std::string, std::string>> earlier;
    for (const auto& model : previous.earlier_models())
      if (!writing.count(model)) earlier.push_back(model);
    folder.remove_earlier_models(earlier, previous.earlier_of_the_same_run());
  }
  // Model files, copied and checked against the hash their shard recorded.
  if (layout.per_building_files) fs::create_directories(fs::path(options.output_dir) / "models");
  for (const detail::RecordInJournal& source : sources) {
    const detail::RecordRef& ref = *source.ref;
    if (ref.model_file.empty()) continue;
    const fs::path from = fs::path(source.journal->path()).parent_path() / "models" / ref.model_file;
    std::ifstream in(from, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) bytes.clear();
    if (!in || detail::content_hash(bytes) != ref.model_hash)
      throw IoError("merge: " + from.string() + " is missing or changed since its shard wrote it; run that shard again");
    detail::AtomicFile copy((fs::path(options.output_dir) / "models" / ref.model_file).string());
    std::fwrite(bytes.data(), 1, bytes.size(), copy.file());
    copy.commit();
  }
  // The merged folder's journal, as one process would have left it: a later run of the same inputs
  // and parameters into it resumes every building. Its lines are copied one at a time: the journals of
  // a region's shards can be gigabytes.
  detail::write_journal((fs::path(options.output_dir) / "resume.journal").string(), whole, sources.size(),
                        [&sources](std::size_t k) { return sources[k].journal->line(*sources[k].ref); });
  double seconds = 0.0;
  for (const Shard& s : shards) seconds += s.manifest.seconds;
  detail::RunManifest manifest;
  manifest.header = whole;
  manifest.records = sources.size();
  BatchSummary summary =
      detail::finalise_run(options.output_dir, layout, sources, seconds, 0, detail::FinaliseScope::whole_run,
                           manifest.outputs, static_cast<unsigned>(std::max(1, options.threads)));
  summary.advice = detail::advice_for(summary, nullptr, "");
  manifest.seconds = seconds;
  folder.write_manifest(manifest);
  log_info("merge: " + std::to_string(shards.size()) + " shards, " + std::to_string(sources.size()) +
           " buildings in " + std::to_string(seconds_since(start)) + " s");
  return summary;
}

}  // namespace city3d
