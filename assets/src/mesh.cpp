// Mesh import through assimp into plain z-up triangle meshes.
#include "simreel/assets/mesh.hpp"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <type_traits>
#include <utility>
#include <cstdio>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <new>
#include <sstream>
#include <string>

namespace simreel::assets {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

/// glTF by specification; others when their metadata names y as the up axis (see mesh.hpp).
bool is_y_up(const std::filesystem::path& path, const aiScene& scene) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".gltf" || ext == ".glb") return true;
  if (scene.mMetaData != nullptr) {
    int up = -1;
    if (scene.mMetaData->Get("UpAxis", up)) return up == 1;
  }
  return false;
}

MeshMaterial read_material(const aiMaterial& m, const std::filesystem::path& folder) {
  MeshMaterial out;
  aiString name;
  if (m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
  aiColor4D c;
  if (m.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS)
    out.base_color = {c.r, c.g, c.b, c.a};
  aiString tex;
  if (m.GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
      m.GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS) {
    const std::string t = tex.C_Str();
    out.texture = !t.empty() && t[0] == '*' ? std::filesystem::path(t) : folder / t;
  }
  return out;
}

/// Bytes of address space the process uses now (/proc/self/statm), 0 if unknown.
std::uint64_t address_space_in_use() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long long pages = 0;
  const bool ok = std::fscanf(f, "%llu", &pages) == 1;
  std::fclose(f);
  const long page = ::sysconf(_SC_PAGESIZE);
  return ok && page > 0 ? pages * std::uint64_t(page) : 0;
}

/// For its lifetime, caps the address space at what is in use plus `budget` bytes, so an import
/// whose file declares billions of elements fails its allocation (std::bad_alloc) instead of
/// taking the machine's memory. Nothing is changed where a limit is already set or the use is
/// unknown. It is set in the import's child process (import_isolated), so it bounds that alone
/// (in this process only where the process cannot fork).
class AddressSpaceBudget {
 public:
  explicit AddressSpaceBudget(std::uint64_t budget) {
#if defined(__SANITIZE_ADDRESS__)
    // AddressSanitizer reserves terabytes of shadow address space and must grow it freely: an
    // address-space cap makes every later allocation fail. Sanitizer builds import uncapped.
    return;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return;  // clang's spelling of the same check
#endif
#endif
    const std::uint64_t used = address_space_in_use();
    if (used == 0 || ::getrlimit(RLIMIT_AS, &old_) != 0 || old_.rlim_cur != RLIM_INFINITY) return;
    rlimit capped = old_;
    capped.rlim_cur = rlim_t(used + budget);
    active_ = ::setrlimit(RLIMIT_AS, &capped) == 0;
  }
  ~AddressSpaceBudget() {
    if (active_) ::setrlimit(RLIMIT_AS, &old_);
  }
  AddressSpaceBudget(const AddressSpaceBudget&) = delete;
  AddressSpaceBudget& operator=(const AddressSpaceBudget&) = delete;

 private:
  rlimit old_{};
  bool active_ = false;
};

/// Throws AssetError naming `file` and the first vertex of `scene` with a coordinate that is NaN
/// or infinite (a float beyond 3.4e38 reads as infinite).
void refuse_non_finite(const aiScene& scene, const std::string& file) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& am = *scene.mMeshes[m];
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      const aiVector3D& p = am.mVertices[v];
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) continue;
      std::ostringstream msg;
      msg << file << ": cannot import mesh: a vertex at (" << p.x << ", " << p.y << ", " << p.z
          << ") (mesh " << m << ", vertex " << v << " as imported), expected finite coordinates "
          << "(at most 3.4e38 in size: they are read as 32-bit floats)";
      throw AssetError(msg.str());
    }
  }
}

}  // namespace

/// The size in bytes of `path`, a regular file within the size limit.
/// @throws AssetError naming the file when it is missing, not a regular file or too large.
static std::uintmax_t checked_size(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw AssetError(file + ": cannot import mesh: no such file");
  // A FIFO would block the import, /dev/zero would never end.
  if (!std::filesystem::is_regular_file(status))
    throw AssetError(file + ": cannot import mesh: not a regular file (a directory, device or FIFO)");
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec || bytes > kMaxMeshFileBytes)
    throw AssetError(file + ": cannot import mesh: " + (ec ? ec.message() : std::to_string(bytes) + " bytes") +
                     ", expected at most " + std::to_string(kMaxMeshFileBytes) + " (the mesh file size limit)");
  return bytes;
}

/// Checks the file and reads it with `importer` (the steps of load_mesh; with `keep_groups`, the
/// node hierarchy is kept so meshes are not joined by material). Returns the scene.
/// @throws AssetError as load_mesh.
static const aiScene* import_scene(Assimp::Importer& importer, const std::filesystem::path& path,
                                   bool keep_groups) {
  constexpr std::size_t kMaxReason = 240;  // characters of assimp's reason kept in the message
  const std::string file = path.string();
  (void)checked_size(path);
  if (keep_groups) importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  // Points and lines are removed rather than imported as degenerate triangles.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // ValidateDataStructure first: a malformed file (assimp's own corpus has some) becomes an error
  // instead of a crash or an assertion in the later steps.
  // The vertices are checked as the file gives them, before the post-processing: joining
  // identical vertices compares positions, and a NaN one was merged into some other vertex (an
  // OBJ "v 1 1 nan" silently became a copy of a neighbour) instead of being refused.
  const aiScene* scene = nullptr;
  const auto refuse_broken = [&] {
    if (scene && !(scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) && scene->mRootNode) return;
    std::string reason = importer.GetErrorString();
    std::replace(reason.begin(), reason.end(), '\n', ' ');
    if (reason.empty()) reason = "unknown assimp error";
    // Some of assimp's reasons quote the rest of the file ("Cannot parse string \"...\" as a
    // real number" quoted 1.8 MB of an STL file): one line is kept readable.
    if (reason.size() > kMaxReason)
      reason = reason.substr(0, kMaxReason) + "... (" + std::to_string(reason.size() - kMaxReason) + " more characters)";
    throw AssetError(file + ": cannot import mesh: " + reason);
  };
  try {
    const AddressSpaceBudget budget(kMaxMeshImportBytes);
    scene = importer.ReadFile(file, aiProcess_ValidateDataStructure);
    refuse_broken();
    refuse_non_finite(*scene, file);
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                         aiProcess_GenSmoothNormals | aiProcess_SortByPType |
                                         aiProcess_PreTransformVertices);
  } catch (const std::bad_alloc&) {
    throw AssetError(file + ": cannot import mesh: needs more than " + std::to_string(kMaxMeshImportBytes >> 20) +
                     " MiB of memory (the mesh import memory limit)");
  }
  refuse_broken();
  // Node transforms can take finite positions beyond float's range.
  refuse_non_finite(*scene, file);
  return scene;
}

/// load_mesh() in this process (no isolation).
static TriangleMesh read_mesh(const std::filesystem::path& path) {
  const std::string file = path.string();
  Assimp::Importer importer;
  const aiScene* scene = import_scene(importer, path, false);
  const bool y_up = is_y_up(path, *scene);
  auto to_z_up = [y_up](const aiVector3D& p) {
    return y_up ? Eigen::Vector3f(p.x, -p.z, p.y) : Eigen::Vector3f(p.x, p.y, p.z);
  };
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    vertices += scene->mMeshes[m]->mNumVertices;
    triangles += scene->mMeshes[m]->mNumFaces;
  }
  if (vertices > kMaxMeshVertices || triangles > kMaxMeshTriangles)
    throw AssetError(file + ": cannot import mesh: " + std::to_string(vertices) + " vertices and " +
                     std::to_string(triangles) + " faces, expected at most " + std::to_string(kMaxMeshVertices) +
                     " and " + std::to_string(kMaxMeshTriangles) + " (the mesh size limit)");
  TriangleMesh mesh;
  const std::filesystem::path folder = path.parent_path();
  for (unsigned k = 0; k < scene->mNumMaterials; ++k)
    mesh.materials.push_back(read_material(*scene->mMaterials[k], folder));
  if (mesh.materials.empty()) mesh.materials.emplace_back();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      mesh.positions.push_back(to_z_up(am->mVertices[v]));
      Eigen::Vector3f n = am->mNormals ? to_z_up(am->mNormals[v]) : Eigen::Vector3f::UnitZ();
      if (!(n.norm() > 0.0f) || !n.allFinite()) n = Eigen::Vector3f::UnitZ();  // degenerate faces
      mesh.normals.push_back(n.normalized());
      mesh.uvs.emplace_back(am->mTextureCoords[0] ? am->mTextureCoords[0][v].x : 0.0f,
                            am->mTextureCoords[0] ? am->mTextureCoords[0][v].y : 0.0f);
    }
    const std::uint32_t material = std::min<std::uint32_t>(am->mMaterialIndex, std::uint32_t(mesh.materials.size() - 1));
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
      mesh.triangle_material.push_back(material);
    }
  }
  if (mesh.triangles.empty()) throw AssetError(file + ": cannot import mesh: the file has no triangles");
  return mesh;
}

/// load_mesh_groups() in this process (no isolation).
static std::vector<MeshGroup> read_mesh_groups(const std::filesystem::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = import_scene(importer, path, true);
  const bool y_up = is_y_up(path, *scene);
  std::vector<MeshGroup> groups;
  const auto add = [&](const std::string& name, const aiMesh& am) {
    if (name.empty() || !(am.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const MeshGroup& g) { return g.name == name; });
    if (it == groups.end()) it = groups.insert(groups.end(), MeshGroup{name, {}});
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      const aiVector3D& p = am.mVertices[v];
      it->positions.push_back(y_up ? Eigen::Vector3f(p.x, -p.z, p.y) : Eigen::Vector3f(p.x, p.y, p.z));
    }
  };
  // Node names (OBJ "o"/"g", glTF nodes) and mesh names (glTF meshes), depth first in file order.
  std::vector<const aiNode*> stack{scene->mRootNode};
  while (!stack.empty()) {
    const aiNode* node = stack.back();
    stack.pop_back();
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const aiMesh& am = *scene->mMeshes[node->mMeshes[k]];
      if (node != scene->mRootNode) add(node->mName.C_Str(), am);
      if (std::string(am.mName.C_Str()) != node->mName.C_Str()) add(am.mName.C_Str(), am);
    }
    for (unsigned c = node->mNumChildren; c-- > 0;) stack.push_back(node->mChildren[c]);
  }
  return groups;
}


// ---- The import in a child process ----------------------------------------------------------
//
// assimp 5.2 does not survive every malformed file: a PLY header without "end_header" makes its
// stream reader seek back to the start and read the file forever, and a PLY file cut short in
// its faces trips an ai_assert in the triangulation that aborts the process. A file cannot be
// shown safe before assimp reads it, so assimp reads it in a forked child: the parent receives
// the plain mesh through a pipe, and a crash, an abort or a loop in the child becomes an
// AssetError naming the file. The memory cap (AddressSpaceBudget) then bounds the child alone.

namespace {

/// The plain arrays of an import, written by the child and read back by the parent (host byte
/// order: both are this program).
class Wire {
 public:
  void put(const void* p, std::size_t n) { bytes_.append(static_cast<const char*>(p), n); }
  void put_u64(std::uint64_t v) { put(&v, sizeof v); }
  void put_string(const std::string& v) {
    put_u64(v.size());
    put(v.data(), v.size());
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_standard_layout_v<T>);  // plain floats and integers (Eigen's fixed vectors too)
    put_u64(v.size());
    put(v.data(), v.size() * sizeof(T));
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

/// Reads what Wire wrote; any read past the end throws AssetError (a child that ended early).
class WireReader {
 public:
  WireReader(const std::string& bytes, std::size_t at, std::string file)
      : p_(bytes.data() + at), end_(bytes.data() + bytes.size()), file_(std::move(file)) {}
  [[noreturn]] void truncated() const {
    throw AssetError(file_ + ": cannot import mesh: the import process sent a truncated result");
  }
  void get(void* out, std::size_t n) {
    if (std::size_t(end_ - p_) < n) truncated();
    if (n == 0) return;  // an empty vector's data() may be null, which memcpy may not take
    std::memcpy(out, p_, n);
    p_ += n;
  }
  std::uint64_t get_u64() {
    std::uint64_t v = 0;
    get(&v, sizeof v);
    return v;
  }
  std::string get_string() {
    const std::uint64_t n = get_u64();
    if (n > std::uint64_t(end_ - p_)) truncated();
    std::string v(p_, std::size_t(n));
    p_ += n;
    return v;
  }
  template <class T>
  std::vector<T> get_vector() {
    const std::uint64_t n = get_u64();
    if (n > std::uint64_t(end_ - p_) / sizeof(T)) truncated();
    std::vector<T> v(static_cast<std::size_t>(n));
    get(v.data(), v.size() * sizeof(T));
    return v;
  }

 private:
  const char* p_;
  const char* end_;
  std::string file_;
};

void put_mesh(Wire& w, const TriangleMesh& m) {
  w.put_vector(m.positions);
  w.put_vector(m.normals);
  w.put_vector(m.uvs);
  w.put_vector(m.triangles);
  w.put_vector(m.triangle_material);
  w.put_u64(m.materials.size());
  for (const MeshMaterial& mat : m.materials) {
    w.put_string(mat.name);
    w.put(mat.base_color.data(), sizeof mat.base_color);
    w.put_string(mat.texture.string());
  }
}

TriangleMesh get_mesh(WireReader& r) {
  TriangleMesh m;
  m.positions = r.get_vector<Eigen::Vector3f>();
  m.normals = r.get_vector<Eigen::Vector3f>();
  m.uvs = r.get_vector<Eigen::Vector2f>();
  m.triangles = r.get_vector<std::array<std::uint32_t, 3>>();
  m.triangle_material = r.get_vector<std::uint32_t>();
  const std::uint64_t n = r.get_u64();
  for (std::uint64_t k = 0; k < n; ++k) {
    MeshMaterial mat;
    mat.name = r.get_string();
    r.get(mat.base_color.data(), sizeof mat.base_color);
    mat.texture = r.get_string();
    m.materials.push_back(std::move(mat));
  }
  return m;
}

void put_groups(Wire& w, const std::vector<MeshGroup>& groups) {
  w.put_u64(groups.size());
  for (const MeshGroup& g : groups) {
    w.put_string(g.name);
    w.put_vector(g.positions);
  }
}

std::vector<MeshGroup> get_groups(WireReader& r) {
  std::vector<MeshGroup> groups;
  const std::uint64_t n = r.get_u64();
  for (std::uint64_t k = 0; k < n; ++k) {
    MeshGroup g;
    g.name = r.get_string();
    g.positions = r.get_vector<Eigen::Vector3f>();
    groups.push_back(std::move(g));
  }
  return groups;
}

/// Seconds one import may run: $SIMREEL_MESH_IMPORT_SECONDS when it is a positive number, else
/// 10 s plus 1 s per 2 MiB of file (138 s at the 256 MiB limit; assimp reads tens of MB/s).
double import_seconds(std::uintmax_t bytes) {
  if (const char* env = std::getenv("SIMREEL_MESH_IMPORT_SECONDS"); env != nullptr && *env != '\0') {
    char* end = nullptr;
    const double s = std::strtod(env, &end);
    if (end != env && *end == '\0' && s > 0.0 && s <= 1e6) return s;
  }
  return 10.0 + double(bytes) / double(2u << 20);
}

/// The last non-empty line of what the child wrote to its stdout and stderr (assimp's assertion
/// message, say), at most 300 characters; "" if none.
std::string last_line(int fd) {
  if (fd < 0) return "";
  std::string text;
  char buf[4096];
  const off_t size = ::lseek(fd, 0, SEEK_END);
  ::lseek(fd, size > off_t(sizeof buf) ? size - off_t(sizeof buf) : 0, SEEK_SET);
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) text.append(buf, std::size_t(n));
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  const std::size_t nl = text.find_last_of('\n');
  if (nl != std::string::npos) text.erase(0, nl + 1);
  std::replace_if(text.begin(), text.end(), [](unsigned char c) { return c < 32; }, ' ');
  if (text.size() > 300) text.resize(300);
  return text;
}

void write_all(int fd, const char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t k = ::write(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return;  // the parent is gone or gave up
    p += k;
    n -= std::size_t(k);
  }
}

/// Runs `encode` (which reads the file with assimp and writes its result into a Wire) in a
/// forked child with a time limit and returns what it wrote: a status byte ('M'), then the
/// result. An
/// AssetError in the child is thrown again here; a child that crashes, aborts, is killed or
/// passes the time limit becomes an AssetError naming `path`. Where the process cannot fork
/// (no memory or process slots), the import runs here instead: the same result, unguarded.
/// Imports run while a scene loads, before simreel starts other threads, so the child is a
/// copy of a single-threaded process.
template <class Encode>
std::string import_isolated(const std::filesystem::path& path, Encode encode) {
  const std::string file = path.string();
  const double seconds = import_seconds(checked_size(path));
  const auto in_child_or_here = [&](Wire& w) {
    try {
      encode(w);
      w.bytes().insert(w.bytes().begin(), 'M');
    } catch (const AssetError& e) {
      w.bytes() = std::string("E") + e.what();
    } catch (const std::exception& e) {
      w.bytes() = "E" + file + ": cannot import mesh: " + e.what();
    }
  };
  const auto here = [&] {
    Wire w;
    in_child_or_here(w);
    if (w.bytes()[0] == 'E') throw AssetError(w.bytes().substr(1));
    return std::move(w.bytes());
  };
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return here();
  // The child's stdout and stderr go to an anonymous file, read back only for an error message.
  const int out = ::memfd_create("simreel-mesh-import", MFD_CLOEXEC);
  const pid_t pid = ::fork();
  if (pid == 0) {
    // The parent's handlers (removing its temporaries on an interrupt) are not the child's:
    // an interrupt ends the child, and the parent handles it.
    for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::signal(sig, SIG_DFL);
    sigset_t none;
    ::sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::close(fds[0]);
    const int sink = out >= 0 ? out : ::open("/dev/null", O_WRONLY);
    if (sink >= 0) {
      ::dup2(sink, STDOUT_FILENO);
      ::dup2(sink, STDERR_FILENO);
    }
    const rlimit no_core{0, 0};  // a malformed file leaves no core dump behind
    ::setrlimit(RLIMIT_CORE, &no_core);
    Wire w;
    in_child_or_here(w);
    write_all(fds[1], w.bytes().data(), w.bytes().size());
    ::_exit(0);
  }
  ::close(fds[1]);
  if (pid < 0) {
    ::close(fds[0]);
    if (out >= 0) ::close(out);
    return here();
  }
  std::string got;
  bool timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  char buf[1 << 16];
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0.0) {
      timed_out = true;
      break;
    }
    pollfd pfd{fds[0], POLLIN, 0};
    const int ready = ::poll(&pfd, 1, int(std::min(left * 1000.0 + 1.0, 60000.0)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // the deadline is checked above
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // the child closed the pipe: it ended
    got.append(buf, std::size_t(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string said = last_line(out);
  if (out >= 0) ::close(out);
  const std::string assimp_said = said.empty() ? "" : " (assimp: \"" + said + "\")";
  if (timed_out) {
    std::ostringstream msg;
    msg << file << ": cannot import mesh: assimp did not finish reading it within " << seconds
        << " s, so the file is probably malformed (assimp loops on some broken files)" << assimp_said
        << "; a large valid file may need more time: set SIMREEL_MESH_IMPORT_SECONDS";
    throw AssetError(msg.str());
  }
  if (WIFSIGNALED(status)) {
    const char* name = sigabbrev_np(WTERMSIG(status));
    throw AssetError(file + ": cannot import mesh: assimp crashed reading it (signal " +
                     (name != nullptr ? std::string("SIG") + name : std::to_string(WTERMSIG(status))) +
                     "), so the file is malformed" + assimp_said);
  }
  if (got.empty() || (got[0] != 'M' && got[0] != 'E'))
    throw AssetError(file + ": cannot import mesh: the import process ended without a result" + assimp_said);
  if (got[0] == 'E') throw AssetError(got.substr(1));
  return got;
}

}  // namespace

TriangleMesh load_mesh(const std::filesystem::path& path) {
  const std::string bytes = import_isolated(path, [&](Wire& w) { put_mesh(w, read_mesh(path)); });
  WireReader r(bytes, 1, path.string());
  return get_mesh(r);
}

std::vector<MeshGroup> load_mesh_groups(const std::filesystem::path& path) {
  const std::string bytes = import_isolated(path, [&](Wire& w) { put_groups(w, read_mesh_groups(path)); });
  WireReader r(bytes, 1, path.string());
  return get_groups(r);
}

}  // namespace simreel::assets
