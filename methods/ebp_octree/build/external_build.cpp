// External-memory build of the `.ebp` store. See external_build.hpp and OUT_OF_CORE.md
// ("`bvhbench ebp build`"): streamed mesh, sorted runs spilled and merged, leaves and inner nodes
// built in octcode order by the in-memory builder's code, pages written as subtrees complete,
// colouring over the node skeleton patched into the pages at the end.
#include "methods/ebp_octree/build/external_build.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <queue>
#include <thread>
#include <stdexcept>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "harness/util/atomic_file.hpp"
#include "methods/ebp_octree/build/assembler.hpp"
#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/external_sort.hpp"
#include "methods/ebp_octree/build/mesh_source.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/store_file.hpp"

namespace ebp {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The frame pass (phase 1): bounding box and edge sum in input order (FrameAccumulator), and
/// whether the mesh is closed (every undirected edge used equally often both ways: two hashed sums
/// of the directed edges are zero; only for fewer than 2^31 vertices).
struct FrameScan {
  FrameAccumulator acc;
  bool closed = false;
};
FrameScan scan_frame(TriangleSource& src, tbb::task_arena& arena, const ExtBuildOptions& opt) {
  auto progress = [&](const char* phase, double f) {
    if (opt.progress) opt.progress(phase, f);
  };
  auto check = [&] {
    if (opt.check) opt.check();
  };
  FrameScan out;
  FrameAccumulator& acc = out.acc;
  std::uint64_t s1 = 0, s2 = 0;
  const bool check_closed = src.num_vertices() < (std::uint64_t(1) << 31);
  {
    // Per chunk, in parallel: each triangle's edge-length sum (the very expression
    // FrameAccumulator::add adds), per-block boxes and closedness sums; then the edge sums are
    // added in input order, so the total is the in-memory build's double, bit for bit.
    constexpr std::size_t kBlock = 4096;
    std::vector<double> edge(kScanChunk);
    std::vector<Box3d> boxes(kScanChunk / kBlock + 1);
    std::vector<std::uint64_t> h1(kScanChunk / kBlock + 1), h2(kScanChunk / kBlock + 1);
    prefetch_scan(src, [&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
      if (edge.size() < n) {
        edge.resize(n);
        boxes.resize(n / kBlock + 1);
        h1.resize(n / kBlock + 1);
        h2.resize(n / kBlock + 1);
      }
      const std::size_t nb = (n + kBlock - 1) / kBlock;
      auto block = [&](std::size_t bi) {
        Box3d bb;
        std::uint64_t a1 = 0, a2 = 0;
        for (std::size_t i = bi * kBlock; i < std::min(n, (bi + 1) * kBlock); ++i) {
          const float* v = xyz + 9 * i;
          const Vec3d a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
          bb.add(a); bb.add(b); bb.add(c);
          edge[i] = perimeter(a, b, c);
          if (check_closed)
            for (int k = 0; k < 3; ++k) {
              const std::uint64_t u = idx[3 * i + std::size_t(k)], w = idx[3 * i + std::size_t((k + 1) % 3)];
              if (u == w) continue;
              a1 += mix64(u << 32 | w) - mix64(w << 32 | u);
              a2 += mix64((w << 32 | u) ^ 0x5851f42d4c957f2dull) - mix64((u << 32 | w) ^ 0x5851f42d4c957f2dull);
            }
        }
        boxes[bi] = bb;
        h1[bi] = a1;
        h2[bi] = a2;
      };
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 1), [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t bi = r.begin(); bi != r.end(); ++bi) block(bi);
        });
      });
      for (std::size_t bi = 0; bi < nb; ++bi) {
        acc.bb.add(boxes[bi]);
        s1 += h1[bi];
        s2 += h2[bi];
      }
      for (std::size_t i = 0; i < n; ++i) acc.edge_sum += edge[i];
      acc.triangles += n;
      if ((first / kScanChunk) % 16 == 0) {
        check();
        if (src.num_triangles()) progress("frame", std::min(0.05, 0.05 * double(first) / double(src.num_triangles())));
      }
    });
  }
  out.closed = check_closed && s1 == 0 && s2 == 0;
  return out;
}

/// The records after phase 2: spilled sorted runs (`runs`, their `files`), or, when every record
/// fitted one run, that run sorted in memory (`runs` empty).
struct SortedRecords {
  TempFiles files;
  std::vector<RunFile> runs;
  std::vector<Rec> run;
};

/// The distribution pass (phase 2): every triangle's (leaf cell, triangle) records, in runs of at
/// most `run_cap` records, each sorted and spilled to opt.tmp_dir when full, into `sorted`.
void distribute_to_runs(TriangleSource& src, const BuildContext& ctx, tbb::task_arena& arena,
                        const ExtBuildOptions& opt, std::uint64_t nt, std::size_t run_cap, ExtBuildReport& R,
                        SortedRecords& sorted) {
  auto progress = [&](const char* phase, double f) {
    if (opt.progress) opt.progress(phase, f);
  };
  auto check = [&] {
    if (opt.check) opt.check();
  };
  TempFiles& run_files = sorted.files;
  std::vector<RunFile>& runs = sorted.runs;
  std::vector<Rec>& run = sorted.run;
  run.reserve(std::min<std::size_t>(run_cap, std::size_t(nt) * 3 + 64));
  auto sort_run = [&] {
    arena.execute([&] { tbb::parallel_sort(run.begin(), run.end(), RecLess()); });
  };
  auto spill = [&] {
    if (run.empty()) return;
    sort_run();
    RunFile rf;
    rf.path = opt.tmp_dir + "/run-" + std::to_string(runs.size()) + ".bin";
    run_files.paths.push_back(rf.path);
    write_run(rf.path, run);
    rf.records = run.size();
    R.spill_bytes += run.size() * sizeof(Rec);
    runs.push_back(rf);
    run.clear();
  };
  {
    tbb::enumerable_thread_specific<std::vector<Rec>> local;
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> local_ms;
    prefetch_scan(src, [&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
      check();
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
          auto& out = local.local();
          auto& ms = local_ms.local();
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const float* v = xyz + 9 * i;
            ms.clear();
            distribute_triangle(ctx, {v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}, ms);
            Rec rec;
            rec.t = std::uint32_t(first + i);
            std::memcpy(rec.v, idx + 3 * i, sizeof rec.v);
            for (std::uint64_t m : ms) {
              rec.m = m;
              out.push_back(rec);
            }
          }
        });
      });
      for (auto& v : local) {
        std::size_t k = 0;
        while (k < v.size()) {
          if (run.size() == run_cap) spill();
          const std::size_t take = std::min(v.size() - k, run_cap - run.size());
          run.insert(run.end(), v.begin() + std::ptrdiff_t(k), v.begin() + std::ptrdiff_t(k + take));
          k += take;
        }
        R.records += v.size();
        v.clear();
      }
      progress("distributing", 0.05 + 0.3 * double(first + n) / double(nt));
    });
    for (auto& v : local) std::vector<Rec>().swap(v);
  }
  if (!runs.empty()) {
    spill();
    std::vector<Rec>().swap(run);
  } else {
    sort_run();
  }
  R.runs = runs.empty() ? 1 : runs.size();
}

/// The sorted records in order: a heap over the spilled runs' readers (their buffers sharing
/// `merge_bytes`), or the one run kept in memory.
class RecordMerge {
 public:
  RecordMerge(SortedRecords& sorted, std::size_t merge_bytes) : sorted_(sorted) {
    const std::vector<RunFile>& runs = sorted.runs;
    for (const RunFile& rf : runs)
      readers_.push_back(std::make_unique<RunReader>(rf, merge_bytes / std::max<std::size_t>(1, runs.size()) / sizeof(Rec)));
    for (std::uint32_t i = 0; i < readers_.size(); ++i)
      if (const Rec* r = readers_[i]->peek()) heap_.push({r->m, r->t, i});
  }
  /// The next record into *out; false at the end.
  bool next(Rec* out) {
    if (sorted_.runs.empty()) {
      if (mem_pos_ == sorted_.run.size()) return false;
      *out = sorted_.run[mem_pos_++];
      return true;
    }
    if (heap_.empty()) return false;
    const HeapEnt h = heap_.top();
    heap_.pop();
    *out = *readers_[h.run]->peek();
    readers_[h.run]->pop();
    if (const Rec* r = readers_[h.run]->peek()) heap_.push({r->m, r->t, h.run});
    return true;
  }

 private:
  struct HeapEnt {
    std::uint64_t m;
    std::uint32_t t, run;
    bool operator>(const HeapEnt& o) const { return m > o.m || (m == o.m && t > o.t); }
  };
  SortedRecords& sorted_;
  std::vector<std::unique_ptr<RunReader>> readers_;
  std::priority_queue<HeapEnt, std::vector<HeapEnt>, std::greater<HeapEnt>> heap_;
  std::size_t mem_pos_ = 0;
};

/// One batch of built leaves, in Morton order, for the assembler.
struct BuiltLeaves {
  std::vector<std::uint64_t> m;
  std::vector<Node> nodes;
  std::vector<Leaf> leaves;
  std::vector<std::vector<LeafTri>> blocks;
  std::vector<NodeTmp> tmps;
  std::vector<LeafHalves> halves;
};

/// A batch of records (leaf cells starting at `starts`, which ends with the batch's size) built
/// into leaves, in parallel when threads > 1. The coordinates are gathered from the source in one
/// call before the parallel builds: a paged source serves one caller at a time.
BuiltLeaves build_batch(TriangleSource& src, const BuildContext& ctx, tbb::task_arena& arena, int threads,
                        const std::vector<Rec>& batch, const std::vector<std::size_t>& starts) {
  const std::size_t nl = starts.size() - 1;
  BuiltLeaves bt;
  bt.m.resize(nl);
  bt.nodes.resize(nl);
  bt.leaves.resize(nl);
  bt.blocks.resize(nl);
  bt.tmps.resize(nl);
  bt.halves.resize(nl);
  std::vector<std::uint32_t> batch_vertices(3 * batch.size());
  std::vector<float> batch_xyz(9 * batch.size());
  for (std::size_t k = 0; k < batch.size(); ++k) std::memcpy(&batch_vertices[3 * k], batch[k].v, sizeof batch[k].v);
  src.gather_vertices(batch_vertices.data(), batch_vertices.size(), batch_xyz.data());
  auto one = [&](std::size_t i) {
    const std::size_t b = starts[i], e = starts[i + 1];
    std::vector<std::uint32_t> tri(e - b);
    for (std::size_t k = b; k < e; ++k) tri[k - b] = batch[k].t;
    bt.blocks[i].resize(e - b);
    bt.m[i] = batch[b].m;
    const Octcode code = octcode_make(ctx.f.leaf_level, batch[b].m);
    build_leaf(ctx, code, e - b, tri.data(), &batch_xyz[9 * b], &bt.nodes[i], &bt.leaves[i], bt.blocks[i].data(),
               &bt.tmps[i], &bt.halves[i]);
  };
  if (threads <= 1 || nl < 2) {
    for (std::size_t i = 0; i < nl; ++i) one(i);
  } else {
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nl, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) one(i);
      });
    });
  }
  return bt;
}

/// The assembler on a thread of its own, fed built batches through a queue of one: at most 3
/// batches alive (being built, queued, being assembled). Its error, if any, is kept for rethrow().
class AssemblerThread {
 public:
  explicit AssemblerThread(Assembler& as) : as_(as), thread_([this] { run(); }) {}
  /// Queues a batch, waiting while one is queued; false if the assembler has failed.
  bool push(BuiltLeaves&& bt) {
    {
      std::unique_lock<std::mutex> lk(mu_);
      cv_.wait(lk, [&] { return queue_.empty() || failed_; });
      if (failed_) return false;
      queue_.push_back(std::move(bt));
    }
    cv_.notify_all();
    return true;
  }
  bool failed() {
    std::lock_guard<std::mutex> lk(mu_);
    return failed_;
  }
  /// After a failure on the feeding side: nothing more is assembled, nor finished.
  void abandon() {
    std::lock_guard<std::mutex> lk(mu_);
    failed_ = true;
    queue_.clear();
  }
  /// Lets the queue drain (the assembly finished unless failed) and joins the thread.
  void stop() {
    {
      std::lock_guard<std::mutex> lk(mu_);
      closing_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void rethrow() const {
    if (err_) std::rethrow_exception(err_);
  }

 private:
  void run() {
    try {
      for (;;) {
        BuiltLeaves bt;
        {
          std::unique_lock<std::mutex> lk(mu_);
          cv_.wait(lk, [&] { return !queue_.empty() || closing_; });
          if (queue_.empty()) break;
          bt = std::move(queue_.front());
          queue_.pop_front();
        }
        cv_.notify_all();
        for (std::size_t i = 0; i < bt.m.size(); ++i)
          as_.add_leaf(bt.m[i], bt.nodes[i], bt.leaves[i], std::move(bt.blocks[i]), std::move(bt.tmps[i]), bt.halves[i]);
      }
      if (!failed()) as_.finish();
    } catch (...) {
      std::lock_guard<std::mutex> lk(mu_);
      err_ = std::current_exception();
      failed_ = true;
    }
    cv_.notify_all();
  }
  Assembler& as_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<BuiltLeaves> queue_;
  bool closing_ = false, failed_ = false;
  std::exception_ptr err_;
  std::thread thread_;  // last: starts once everything above exists
};

/// The merge and the assembly (phase 3): the sorted records merged, each leaf cell's records
/// built into a leaf (build_leaf, in parallel batches of ≈ avail/12), the batches handed to the
/// assembler's thread (inner nodes, the cut, the pages written as their subtrees complete).
void merge_and_assemble(TriangleSource& src, const BuildContext& ctx, tbb::task_arena& arena,
                        const ExtBuildOptions& opt, std::size_t avail, ExtBuildReport& R, SortedRecords& sorted,
                        Assembler& as) {
  const int threads = std::max(1, opt.params.threads);
  RecordMerge merge(sorted, avail / 4);
  // A batch's records, their coordinates and its leaves' triangles.
  const std::size_t batch_cap =
      std::max<std::size_t>(4096, (avail / 12) / (sizeof(Rec) + 12 + 36 + sizeof(LeafTri) + 64));
  AssemblerThread assembler(as);
  try {
    std::vector<Rec> batch;
    std::vector<std::size_t> starts;  // the batch's leaf cells
    std::uint64_t consumed = 0;
    auto process = [&] {
      starts.push_back(batch.size());
      if (!assembler.push(build_batch(src, ctx, arena, threads, batch, starts))) return;
      consumed += batch.size();
      batch.clear();
      starts.clear();
      if (opt.check) opt.check();
      if (opt.progress)
        opt.progress("building", 0.35 + 0.6 * double(consumed) / double(std::max<std::uint64_t>(1, R.records)));
    };
    Rec r;
    while (merge.next(&r)) {
      if (batch.empty() || batch.back().m != r.m) {
        if (batch.size() >= batch_cap) {
          process();
          if (assembler.failed()) break;
        }
        starts.push_back(batch.size());
      }
      batch.push_back(r);
    }
    if (!batch.empty() && !assembler.failed()) process();
    std::vector<Rec>().swap(sorted.run);
  } catch (...) {
    assembler.abandon();
    assembler.stop();
    throw;
  }
  assembler.stop();
  assembler.rethrow();
}

/// Writes the colouring into the pages (phase 4): the kind byte of each empty node found black,
/// the winding number of each leaf's reference point (both zero when written), and each patched
/// page's checksum updated from the patch bytes alone.
void patch_colouring(bvhbench::AtomicOutputFile& out, Assembler& as, const Colouring& C,
                     const std::vector<std::uint8_t>& is_black) {
  std::vector<Patch> patches;
  for (const auto& [g, p] : as.white_loc)
    if (is_black[g]) {
      Patch q = p;
      q.len = 1;
      q.b[0] = std::uint8_t(NodeKind::black);
      patches.push_back(q);
    }
  for (std::size_t li = 0; li < as.leaf_loc.size(); ++li)
    if (C.ref_winding[li] != 0) {
      Patch q = as.leaf_loc[li];
      q.len = 2;
      std::memcpy(q.b, &C.ref_winding[li], 2);
      patches.push_back(q);
    }
  std::sort(patches.begin(), patches.end(),
            [](const Patch& a, const Patch& b) { return a.page < b.page || (a.page == b.page && a.off < b.off); });
  {
    // CRC-32C is affine in the message: crc(x ^ d) = crc(x) ^ crc(d) ^ crc(0...0) (same length),
    // and the patched fields are zero before: the new checksum needs only the patch bytes.
    std::vector<std::uint8_t> zero;
    std::uint32_t zero_crc = 0;
    std::size_t zero_len = SIZE_MAX;
    for (std::size_t i = 0; i < patches.size();) {
      std::size_t j = i;
      PageEntry& e = as.dir[patches[i].page];
      if (zero.size() < e.size) zero.resize(e.size, 0);
      if (zero_len != e.size) {
        zero_crc = crc32c(zero.data(), e.size);
        zero_len = e.size;
      }
      for (; j < patches.size() && patches[j].page == patches[i].page; ++j)
        std::memcpy(&zero[patches[j].off], patches[j].b, patches[j].len);
      e.crc ^= crc32c(zero.data(), e.size) ^ zero_crc;
      for (std::size_t k = i; k < j; ++k) {
        out.write_at(e.offset + patches[k].off, patches[k].b, patches[k].len);
        std::memset(&zero[patches[k].off], 0, patches[k].len);
      }
      i = j;
    }
  }
}

/// How the memory budget is shared (opt.memory_budget): the source's resident bytes and a fixed
/// reserve come first; the rest, `avail`, goes to the sort runs (phase 2), then to the merge
/// buffers and the leaf batches (phase 3).
struct MemoryPlan {
  std::size_t avail = 0;
  std::size_t run_cap = 0;  ///< records per sorted run
};
MemoryPlan plan_memory(const TriangleSource& src, std::uint64_t nt, const ExtBuildOptions& opt, ExtBuildReport& R) {
  // Also set aside what grows with the model and is kept to the end: the node skeleton, the
  // union-find, the top tree and the patch list, ≈ 2.2 B per triangle measured on the 32M
  // models (at the default build options); 3 B per triangle is reserved.
  const std::size_t reserve = (std::size_t(48) << 20) + std::size_t(3 * nt);
  const std::size_t resident = src.resident_bytes();
  R.min_budget_bytes = resident + reserve + (std::size_t(8) << 20);
  MemoryPlan plan;
  plan.avail = opt.memory_budget > resident + reserve ? opt.memory_budget - resident - reserve : 0;
  plan.avail = std::max<std::size_t>(plan.avail, std::size_t(8) << 20);
  plan.run_cap = (opt.run_bytes ? opt.run_bytes : plan.avail / 2) / sizeof(Rec);
  plan.run_cap = std::max<std::size_t>(plan.run_cap, 64);
  R.run_capacity_records = plan.run_cap;
  return plan;
}

/// The colouring over the assembler's skeleton (phase 4); the winding-number fallback rescans
/// the source. Returns, per node, whether it is an empty node found black.
std::vector<std::uint8_t> colour_skeleton(TriangleSource& src, const Frame& F, Assembler& as, Colouring* C) {
  auto winding_at = [&](const std::vector<Vec3d>& pts) {
    std::vector<double> w(pts.size(), 0.0);
    src.scan([&](std::uint64_t, std::size_t n, const std::uint32_t*, const float* xyz) {
      for (std::size_t i = 0; i < n; ++i) {
        const float* v = xyz + 9 * i;
        const Vec3d a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
        for (std::size_t k = 0; k < pts.size(); ++k) w[k] += bvhbench::triangle_winding(pts[k], a, b, c);
      }
    });
    std::vector<int> out;
    for (double x : w) out.push_back(int(std::lround(x)));
    return out;
  };
  *C = colour(F, as.sk, winding_at);
  std::vector<std::uint8_t> is_black(as.sk.code.size(), 0);
  for (std::uint32_t i : C->black) is_black[i] = 1;
  return is_black;
}

/// The top tree's black nodes, and its planes gathered in top-node order (the section's content).
std::vector<Plane> finish_top_tree(Assembler& as, const std::vector<std::uint8_t>& is_black) {
  for (std::size_t k = 0; k < as.top.size(); ++k)
    if (as.top[k].kind == TopKind::white && is_black[as.top_gid[k]]) as.top[k].kind = TopKind::black;
  std::vector<Plane> top_planes;
  for (std::size_t k = 0; k < as.top.size(); ++k) {
    as.top[k].plane_begin = std::uint32_t(top_planes.size());
    as.top[k].plane_count = std::uint16_t(as.top_plane_ref[k].second);
    top_planes.insert(top_planes.end(), as.top_plane_pool.begin() + as.top_plane_ref[k].first,
                      as.top_plane_pool.begin() + as.top_plane_ref[k].first + as.top_plane_ref[k].second);
  }
  return top_planes;
}

/// The whole tree's figures (the assembler counted the grey nodes as it went).
void complete_stats(const Frame& F, const BuildContext& ctx, std::uint64_t nt, const Colouring& C,
                    const std::vector<std::uint8_t>& is_black, Assembler& as, const ExtBuildReport& R) {
  Stats& S = as.stats;
  S.leaf_level = F.leaf_level;
  S.root_size = F.root_size;
  S.leaf_size = ctx.cs;
  S.average_edge = F.average_edge;
  S.triangles = nt;
  S.nodes = as.sk.code.size();
  S.planes = as.planes_total_;
  S.colour_fallbacks = C.colour_fallbacks;
  S.degenerate_edges = C.degenerate_edges;
  S.invalid_refs = C.invalid_refs;
  for (std::size_t i = 0; i < S.nodes; ++i)
    if (as.sk.kind[i] == NodeKind::white) ++(is_black[i] ? S.black : S.white);
  S.seconds_distribute = R.seconds_distribute;
  S.seconds_colour = R.seconds_colour;
}

/// The sections after the pages (directory, top tree, info) and the header, written last.
void write_tail(bvhbench::AtomicOutputFile& out, TriangleSource& src, const Frame& F, const ExtBuildOptions& opt,
                Assembler& as, const std::vector<Plane>& top_planes, ExtBuildReport& R) {
  const Stats& S = R.stats;
  FileHeader h = new_file_header(src.origin(), F.root_lo, F.root_size, F.leaf_level, std::uint32_t(S.triangles),
                                 opt.params, opt.page_target, R.closed);
  h.nodes = S.nodes;
  h.inner = S.inner;
  h.leaves = S.leaves;
  h.white = S.white;
  h.black = S.black;
  h.triangle_refs = S.triangle_refs;
  h.planes = S.planes;
  h.num_pages = as.dir.size();
  h.num_top_nodes = as.top.size();
  h.num_top_children = as.top_children.size();
  h.num_top_planes = top_planes.size();
  h.pages.offset = kPageAlign;
  h.pages.size = as.off_ - kPageAlign;
  h.pages.crc = 0;  // each page has its own checksum (in the directory)
  std::uint64_t off = as.off_;
  auto section = [&](const void* data, std::size_t n, Section* s) { write_section(out, &off, data, n, s); };
  section(as.dir.data(), as.dir.size() * sizeof(PageEntry), &h.directory);
  section(as.top.data(), as.top.size() * sizeof(TopNode), &h.top_nodes);
  section(as.top_children.data(), as.top_children.size() * sizeof(std::uint32_t), &h.top_children);
  section(top_planes.data(), top_planes.size() * sizeof(Plane), &h.top_planes);
  const std::string info = opt.info_json ? opt.info_json(R) : std::string("{}");
  section(info.data(), info.size(), &h.info);
  h.file_size = h.info.offset + h.info.size;
  write_header(out, h);
  R.file_bytes = h.file_size;
}

}  // namespace

ExtBuildReport build_store_external(TriangleSource& src, const std::string& path, const ExtBuildOptions& opt) {
  const auto t_start = Clock::now();
  ExtBuildReport R;
  auto progress = [&](const char* phase, double f) {
    if (opt.progress) opt.progress(phase, f);
  };
  auto check = [&] {
    if (opt.check) opt.check();
  };
  tbb::task_arena arena(std::max(1, opt.params.threads));

  // ---- 1. frame (streaming): bounding box, average edge, closedness, sha256 ----
  auto t0 = Clock::now();
  const FrameScan scan = scan_frame(src, arena, opt);
  const std::uint64_t nt = scan.acc.triangles;
  if (nt == 0) throw std::invalid_argument("ebp_octree: the mesh has no triangle");
  if (nt > kMaxTriangles)  // the LeafTri index shares its word with the flags
    throw std::invalid_argument("ebp_octree: " + std::to_string(nt) + " triangles, more than the " +
                                std::to_string(kMaxTriangles) + " a tree can index");
  R.closed = scan.closed;
  const Frame F = compute_frame(scan.acc, opt.params);
  const BuildContext ctx(F, opt.params);
  R.seconds_frame = since(t0);
  progress("frame", 0.05);
  const MemoryPlan plan = plan_memory(src, nt, opt, R);

  // ---- 2. distribution into sorted runs ----
  t0 = Clock::now();
  SortedRecords sorted;
  distribute_to_runs(src, ctx, arena, opt, nt, plan.run_cap, R, sorted);
  R.seconds_distribute = since(t0);
  check();

  // ---- 3. merge; leaves in batches (parallel), inner nodes and pages as subtrees complete ----
  t0 = Clock::now();
  bvhbench::AtomicOutputFile out(path);  // a temporary beside path until committed, removed on failure
  Assembler as(ctx, opt, out, kPageAlign);
  merge_and_assemble(src, ctx, arena, opt, plan.avail, R, sorted, as);
  R.seconds_merge_build = since(t0);
  // The runs are no longer needed.
  for (const std::string& p : sorted.files.paths) ::unlink(p.c_str());
  sorted.files.paths.clear();

  // ---- 4. colouring over the skeleton, patched into the pages and the top tree ----
  t0 = Clock::now();
  progress("colouring", 0.95);
  R.skeleton_bytes = as.sk.bytes();
  Colouring C;
  const std::vector<std::uint8_t> is_black = colour_skeleton(src, F, as, &C);
  patch_colouring(out, as, C, is_black);
  const std::vector<Plane> top_planes = finish_top_tree(as, is_black);
  R.seconds_colour = since(t0);

  // ---- 5. stats, the sections after the pages, the header ----
  complete_stats(F, ctx, nt, C, is_black, as, R);
  as.stats.build_seconds = since(t_start);
  R.stats = as.stats;
  R.pages = as.dir.size();
  R.top_nodes = as.top.size();
  write_tail(out, src, F, opt, as, top_planes, R);
  check();
  out.commit_durable();
  R.seconds_total = since(t_start);
  progress("done", 1.0);
  return R;
}

}  // namespace ebp
