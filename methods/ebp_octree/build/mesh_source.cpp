// The mesh sources of the external build (mesh_source.hpp): in memory, a mesh file through the
// harness's mesh reader, and the prefetching scan.
#include "methods/ebp_octree/build/mesh_source.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "harness/io/mesh_reader.hpp"
#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/vertex_pages.hpp"

namespace ebp {

namespace {

/// xyz[3k..3k+2] = vertex idx[k] of held float vertices vf (x, y, z each).
void gather_held(const std::vector<float>& vf, const std::uint32_t* idx, std::size_t n, float* xyz) {
  for (std::size_t k = 0; k < n; ++k) std::memcpy(xyz + 3 * k, &vf[3 * std::size_t(idx[k])], 3 * sizeof(float));
}

class MemorySource final : public TriangleSource {
 public:
  MemorySource(const std::vector<Vec3d>& v, const std::vector<std::array<std::uint32_t, 3>>& t) : v_(v), t_(t) {
    Box3d bounds;
    for (const Vec3d& p : v_) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::invalid_argument("ebp_octree: non-finite vertex coordinate");
      bounds.add(p);
    }
    origin_ = detail::choose_origin(bounds);
    vf_.reserve(3 * v_.size());
    for (const Vec3d& p : v_)
      for (int k = 0; k < 3; ++k) vf_.push_back(float(p[k] - origin_[k]));
  }
  void gather_vertices(const std::uint32_t* idx, std::size_t n, float* xyz) override { gather_held(vf_, idx, n, xyz); }
  Vec3d origin() const override { return origin_; }
  std::uint64_t num_triangles() const override { return t_.size(); }
  std::uint64_t num_vertices() const override { return v_.size(); }
  void scan(const Chunk& f) override {
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
    for (std::size_t first = 0; first < t_.size(); first += kScanChunk) {
      const std::size_t n = std::min(kScanChunk, t_.size() - first);
      idx.resize(3 * n);
      xyz.resize(9 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t vi = t_[first + i][k];
          if (vi >= v_.size()) throw std::invalid_argument("ebp_octree: vertex index out of range");
          idx[3 * i + k] = vi;
          std::memcpy(&xyz[9 * i + 3 * std::size_t(k)], &vf_[3 * std::size_t(vi)], 3 * sizeof(float));
        }
      f(first, n, idx.data(), xyz.data());
    }
  }
  std::size_t resident_bytes() const override { return vf_.capacity() * sizeof(float); }

 private:
  const std::vector<Vec3d>& v_;
  Vec3d origin_;
  std::vector<float> vf_;
  const std::vector<std::array<std::uint32_t, 3>>& t_;
};

/// A mesh file in any format the harness reads, through its mesh reader (mesh_reader.hpp): the
/// vertices read once into float (held, or paged when they exceed paging.held_limit), the
/// triangles re-read from the file at every scan.
class FileSource final : public TriangleSource {
 public:
  FileSource(const std::string& path, const VertexPaging& paging) : reader_(bvhbench::MeshReader::open(path)) {
    const std::uint64_t nv = reader_->num_vertices();  // the header's count, checked against the file size
    if (nv * 3 * sizeof(float) > paging.held_limit && !paging.tmp_dir.empty())
      pages_ = std::make_unique<VertexPages>(paging.tmp_dir, nv, paging.cache_bytes);
    else
      vf_.reserve(3 * std::size_t(nv));
    Box3d bounds;
    read_vertices([&](const Vec3d& v) {
      bounds.add(v);
      return v;
    });
    origin_ = detail::choose_origin(bounds);
    if (origin_ != Vec3d(0, 0, 0)) {
      // A model far from the origin: its vertices again, from a second reader (a reader delivers
      // its vertices once), as float(v - origin). Holding doubles instead would cost 24 B a vertex.
      reader_ = bvhbench::MeshReader::open(path);
      if (pages_) pages_->rewind();
      vf_.clear();
      read_vertices([&](const Vec3d& v) { return v - origin_; });
    }
    if (pages_) pages_->finish();
    vf_.shrink_to_fit();
  }
  Vec3d origin() const override { return origin_; }
  std::uint64_t num_triangles() const override { return reader_->num_triangles(); }
  std::uint64_t num_vertices() const override { return reader_->num_vertices(); }
  std::string sha256() const override { return reader_->sha256(); }
  void gather_vertices(const std::uint32_t* idx, std::size_t n, float* xyz) override {
    if (pages_)
      pages_->gather(idx, n, xyz);
    else
      gather_held(vf_, idx, n, xyz);
  }
  std::pair<std::uint64_t, std::uint64_t> vertex_page_reads() const override {
    return pages_ ? std::pair{pages_->reads(), pages_->misses()} : std::pair<std::uint64_t, std::uint64_t>{0, 0};
  }
  /// The float vertices or their page cache, the reader's buffers (an STL's weld table among
  /// them) and one chunk.
  std::size_t resident_bytes() const override {
    return vf_.capacity() * sizeof(float) + (pages_ ? pages_->resident_bytes() : 0) + reader_->resident_bytes() +
           kScanChunk * (3 * sizeof(std::uint32_t) + 9 * sizeof(float));
  }
  bool streaming() const override { return true; }

  void scan(const Chunk& f) override {
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
    reader_->read_triangles([&](std::uint64_t first, const bvhbench::Triangle* t, std::size_t n) {
      idx.resize(3 * n);
      xyz.resize(9 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) idx[3 * i + std::size_t(k)] = t[i][k];
      gather_vertices(idx.data(), 3 * n, xyz.data());
      f(first, n, idx.data(), xyz.data());
    });
  }

 private:
  /// Every vertex through `to_frame` (which also sees it first: the bounds), as float, into the
  /// held array or the vertex file.
  template <class ToFrame>
  void read_vertices(ToFrame&& to_frame) {
    std::vector<float> buf;
    reader_->read_vertices([&](std::uint64_t, const Vec3d* v, std::size_t n) {
      buf.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3d w = to_frame(v[i]);
        for (int k = 0; k < 3; ++k) buf[3 * i + std::size_t(k)] = float(w[k]);
      }
      if (pages_)
        pages_->append(buf.data(), n);
      else
        vf_.insert(vf_.end(), buf.begin(), buf.end());
    });
  }

  std::unique_ptr<bvhbench::MeshReader> reader_;
  Vec3d origin_;
  std::vector<float> vf_;               ///< the vertices, when held
  std::unique_ptr<VertexPages> pages_;  ///< the vertices, when paged
};

}  // namespace

std::unique_ptr<TriangleSource> make_memory_source(const std::vector<Vec3d>& vertices,
                                                   const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  return std::make_unique<MemorySource>(vertices, triangles);
}

std::unique_ptr<TriangleSource> open_mesh_source(const std::string& path, const VertexPaging& paging) {
  return std::make_unique<FileSource>(path, paging);
}

void prefetch_scan(TriangleSource& src, const TriangleSource::Chunk& fn) {
  struct Buf {
    std::uint64_t first = 0;
    std::size_t n = 0;
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
  };
  struct Abort {};
  std::mutex mu;
  std::condition_variable cv;
  std::deque<Buf> q;
  std::vector<Buf> spare;
  bool done = false, stop = false;
  std::exception_ptr err;
  std::thread prod([&] {
    try {
      src.scan([&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
        Buf b;
        {
          std::unique_lock<std::mutex> lk(mu);
          cv.wait(lk, [&] { return q.size() < 3 || stop; });
          if (stop) throw Abort{};
          if (!spare.empty()) {
            b = std::move(spare.back());
            spare.pop_back();
          }
        }
        b.first = first;
        b.n = n;
        b.idx.assign(idx, idx + 3 * n);
        b.xyz.assign(xyz, xyz + 9 * n);
        {
          std::lock_guard<std::mutex> lk(mu);
          q.push_back(std::move(b));
        }
        cv.notify_all();
      });
    } catch (const Abort&) {
    } catch (...) {
      err = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lk(mu);
      done = true;
    }
    cv.notify_all();
  });
  try {
    for (;;) {
      Buf b;
      {
        std::unique_lock<std::mutex> lk(mu);
        cv.wait(lk, [&] { return !q.empty() || done; });
        if (q.empty()) break;
        b = std::move(q.front());
        q.pop_front();
      }
      cv.notify_all();
      fn(b.first, b.n, b.idx.data(), b.xyz.data());
      std::lock_guard<std::mutex> lk(mu);
      spare.push_back(std::move(b));
    }
  } catch (...) {
    {
      std::lock_guard<std::mutex> lk(mu);
      stop = true;
    }
    cv.notify_all();
    prod.join();
    throw;
  }
  prod.join();
  if (err) std::rethrow_exception(err);
}

}  // namespace ebp
