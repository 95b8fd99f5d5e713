// Restart files. The whole layout (docs/guide_restart.md) is in two places
// only, write_header/write_body and read_header/read_body, field for field in
// the same order. Every number is little-endian whatever the machine; doubles
// and floats travel as their IEEE bit patterns, so a value comes back with
// every bit it had. Two CRC-32 checksums guard the file: one over the fixed
// header, so that its sizes can be trusted before anything is allocated from
// them, and one over the whole file.
#include "io/restart.hpp"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "model/limits.hpp"
#include "model/mesh_part.hpp"

namespace dpsm {

namespace {

// PNG's trick: a high byte catches 7-bit transfers, CR LF and ^Z catch
// text-mode conversions, before the checksum would.
constexpr std::array<std::uint8_t, 8> kMagic{0x89, 'D', 'P', 'S', 'M', '\r', '\n', 0x1a};
// The fixed header of version 1, its checksum included (docs/guide_restart.md).
constexpr std::size_t kHeaderBytes = 220;
constexpr std::size_t kChecksumBytes = 4;
// The block record of version 2, right after the fixed header.
constexpr std::size_t kBlockBytes = 48;

// Which optional per-cell arrays follow the mandatory ones.
constexpr std::uint32_t kHasSource = 1u << 0;
constexpr std::uint32_t kHasBed = 1u << 1;
constexpr std::uint32_t kHasAngleField = 1u << 2;
constexpr std::uint32_t kHasMoving = 1u << 3;
// Version 2: a block record follows the header (one rank's block of a distributed grid).
constexpr std::uint32_t kIsBlock = 1u << 4;
// Version 2: dpsm_step relaxes to rest (dpsm_set_relaxation); no data of its own.
constexpr std::uint32_t kRelaxToRest = 1u << 5;
// Version 3: dpsm_step relaxes to rest where the scene allows it (DPSM_RELAX_AUTO,
// the default since that version). Without either flag: time-accurate.
constexpr std::uint32_t kRelaxAuto = 1u << 6;
// Version 4, what a host couples: the accounts of what left through each
// side (after the arrays), the levels beyond a side (one flag per side,
// DPSM_XMIN first; its levels follow the accounts), and whether the face
// fluxes are recorded (no data: a loaded grid reads 0 until its next step).
constexpr std::uint32_t kHasSideOutflows = 1u << 7;
constexpr std::uint32_t kHasSideLevelsOfXMin = 1u << 8;  // .. 1u << 11 for DPSM_YMAX
constexpr std::uint32_t kHasSideLevels = 0xfu << 8;
constexpr std::uint32_t kRecordsFluxes = 1u << 12;
// Version 5, unstructured meshes: a mesh record (what the host gave its
// constructor) follows the fixed header and the block record, and the body's
// arrays hold one value per cell in the library's order, which the mesh
// rebuilt from the record has again; with kHasEdgeKinds, which faces of the
// domain edge are open, one byte per face, after the side levels (the levels
// of a mesh's edge are those of side 0, one per face).
constexpr std::uint32_t kIsMesh = 1u << 13;
constexpr std::uint32_t kHasEdgeKinds = 1u << 14;
// Version 6: the mesh record's indices count from 1 (the mesh was made with
// start_index 1, and its messages and dpsm_get_mesh_faces count from 1); no
// data of its own. Without it they count from 0, as in every version 5 file.
constexpr std::uint32_t kMeshFromOne = 1u << 15;
// Version 7: a rank's part of a distributed mesh (with kIsMesh and kIsBlock:
// the block record, then the mesh record of the rank's local cells, then per
// local cell its global id, i64, and its owner's rank, i32). The block record
// holds the global mesh's cells as global_nx (global_ny = 1, i0 = j0 = 0).
constexpr std::uint32_t kMeshPart = 1u << 16;
// Version 8: the mesh record's nodes are longitude and latitude in degrees
// (dpsm_create_mesh_geographic and the dual's); no data of its own.
constexpr std::uint32_t kMeshGeographic = 1u << 17;
// Version 9: dpsm_step takes local time steps (DPSM_RELAX_LOCAL_STEPS); no data of its own.
constexpr std::uint32_t kRelaxLocalSteps = 1u << 18;
constexpr std::uint32_t kKnownFlags = kHasSource | kHasBed | kHasAngleField | kHasMoving | kIsBlock | kRelaxToRest |
                                      kRelaxAuto | kHasSideOutflows | kHasSideLevels | kRecordsFluxes | kIsMesh |
                                      kHasEdgeKinds | kMeshFromOne | kMeshPart | kMeshGeographic | kRelaxLocalSteps;
// The flags a file of version 1 cannot hold, those version 2 cannot, and so on.
constexpr std::uint32_t kVersion2Flags = kIsBlock | kRelaxToRest;
constexpr std::uint32_t kVersion3Flags = kRelaxAuto;
constexpr std::uint32_t kVersion4Flags = kHasSideOutflows | kHasSideLevels | kRecordsFluxes;
constexpr std::uint32_t kVersion5Flags = kIsMesh | kHasEdgeKinds;
constexpr std::uint32_t kVersion6Flags = kMeshFromOne;
constexpr std::uint32_t kVersion7Flags = kMeshPart;
constexpr std::uint32_t kVersion8Flags = kMeshGeographic;
constexpr std::uint32_t kVersion9Flags = kRelaxLocalSteps;
// The fixed part of the mesh record: kind, a reserved word, and four counts.
constexpr std::size_t kMeshRecordBytes = 40;

constexpr std::uint32_t side_levels_flag(int side) { return kHasSideLevelsOfXMin << side; }

// The oldest version that holds a file with these flags.
std::uint32_t version_for(std::uint32_t flags) {
    if (flags & kVersion9Flags) return 9;
    if (flags & kVersion8Flags) return 8;
    if (flags & kVersion7Flags) return 7;
    if (flags & kVersion6Flags) return 6;
    if (flags & kVersion5Flags) return 5;
    if (flags & kVersion4Flags) return 4;
    if (flags & kVersion3Flags) return 3;
    return (flags & kVersion2Flags) ? 2 : 1;
}

// The faces along a side: ny for the x sides, nx for the y sides; on a mesh
// (nfaces > 0) every face of the mesh for side 0, its edge.
std::int64_t faces_along(int side, std::int64_t nx, std::int64_t ny, std::int64_t nfaces = 0) {
    if (nfaces > 0) return nfaces;
    return side < kYMin ? ny : nx;
}

// The counts of a mesh record, and the arrays of what the host gave.
struct MeshRecord {
    std::uint32_t kind = 0;
    std::int64_t nnodes = 0, ncells = 0, nindices = 0, nfaces = 0;
    std::size_t array_bytes() const {
        if (kind == MeshInput::kGraph)
            return static_cast<std::size_t>(ncells) * (16 + 8) + static_cast<std::size_t>(nfaces) * (16 + 16 + 8);
        const std::size_t starts = kind == MeshInput::kPolygons ? static_cast<std::size_t>(ncells + 1) * 8 : 0;
        return static_cast<std::size_t>(nnodes) * 16 + starts + static_cast<std::size_t>(nindices) * 8;
    }
};

MeshRecord record_of(const Mesh &mesh) {
    const MeshInput &in = mesh.input;
    MeshRecord r;
    r.kind = in.kind;
    r.nfaces = mesh.faces;
    if (in.kind == MeshInput::kGraph) {
        r.ncells = in.ncells;
        return r;
    }
    r.nnodes = static_cast<std::int64_t>(in.node_xy.size() / 2);
    r.nindices = static_cast<std::int64_t>(in.cell_nodes.size());
    r.ncells = in.kind == MeshInput::kPolygons ? static_cast<std::int64_t>(in.cell_start.size()) - 1 : r.nindices / 3;
    return r;
}


// ---- CRC-32 (ISO-HDLC, as zlib, PNG and gzip: reflected 0xEDB88320) -------

struct Crc32Table {
    std::array<std::uint32_t, 256> entry{};
    Crc32Table() {
        for (std::uint32_t n = 0; n < 256; ++n) {
            std::uint32_t c = n;
            for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            entry[n] = c;
        }
    }
};

// A running checksum: start at 0, feed bytes, the value is the CRC of all of them.
std::uint32_t crc32_update(std::uint32_t crc, const std::uint8_t *bytes, std::size_t n) {
    static const Crc32Table table;
    std::uint32_t c = ~crc;
    for (std::size_t k = 0; k < n; ++k) c = table.entry[(c ^ bytes[k]) & 0xffu] ^ (c >> 8);
    return ~c;
}

std::string system_reason(int error) {
    const char *reason = std::strerror(error);
    return reason ? reason : "unknown error";
}

// ---- writing ----------------------------------------------------------------

// Serialises little-endian into a buffer that goes to the file in large
// pieces, keeping the running checksum of everything written.
class Writer {
public:
    Writer(std::FILE *file, const std::string &path, const char *function)
        : file_(file), path_(path), function_(function) {
        buffer_.reserve(kFlushBytes + 64);
    }

    void u8(std::uint8_t v) { buffer_.push_back(v); }
    void u32(std::uint32_t v) {
        for (int k = 0; k < 4; ++k) buffer_.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void u64(std::uint64_t v) {
        for (int k = 0; k < 8; ++k) buffer_.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
    void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
    void f64(double v) {
        std::uint64_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        u64(bits);
    }
    void f32(float v) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        u32(bits);
    }
    template <class T, class Put>
    void array(const std::vector<T> &values, Put put) {
        for (const T &v : values) {
            (this->*put)(v);
            if (buffer_.size() >= kFlushBytes) flush();
        }
    }

    // The checksum of everything so far (the buffer included), written next.
    void checksum() { u32(crc32_update(crc_, buffer_.data(), buffer_.size())); }
    std::size_t buffered() const { return buffer_.size(); }

    void flush() {
        if (buffer_.empty()) return;
        crc_ = crc32_update(crc_, buffer_.data(), buffer_.size());
        if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
            fail(DPSM_ERR_IO, function_, "cannot write ", path_, ": ", system_reason(errno));
        buffer_.clear();
    }

private:
    static constexpr std::size_t kFlushBytes = 1 << 20;
    std::FILE *file_;
    const std::string &path_;
    const char *function_;
    std::vector<std::uint8_t> buffer_;
    std::uint32_t crc_ = 0;
};

std::uint32_t flags_of(const Grid &g) {
    std::uint32_t flags = 0;
    if (!g.source().empty()) flags |= kHasSource;
    if (!g.bed().empty()) flags |= kHasBed;
    if (!g.angle_field().empty()) flags |= kHasAngleField;
    if (!g.moving().empty()) flags |= kHasMoving;
    if (g.relaxation() == kToRest) flags |= kRelaxToRest;
    if (g.relaxation() == kAutoRelaxation) flags |= kRelaxAuto;
    if (g.relaxation() == kLocalSteps) flags |= kRelaxLocalSteps;
    for (const CompensatedSum &account : g.ledger().side_outflow)
        if (account.sum() != 0.0 || account.correction() != 0.0) flags |= kHasSideOutflows;
    for (int side = 0; side < 4; ++side)
        if (!g.side_levels(side).empty()) flags |= side_levels_flag(side);
    if (g.records_face_fluxes()) flags |= kRecordsFluxes;
    if (g.geometry().is_mesh()) flags |= kIsMesh;
    if (g.geometry().is_mesh() && g.geometry().mesh->input.start_index == 1) flags |= kMeshFromOne;
    if (g.geometry().is_mesh() && !g.geometry().mesh->input.owner.empty()) flags |= kMeshPart;
    if (g.geometry().is_mesh() && g.geometry().mesh->input.geographic) flags |= kMeshGeographic;
    if (!g.edge_open_flags().empty()) flags |= kHasEdgeKinds;
    return flags;
}

void write_header(Writer &w, const Grid &g, const RestartBlock &block) {
    const Geometry &geo = g.geometry();
    for (const std::uint8_t b : kMagic) w.u8(b);
    // The oldest version that holds the grid, so that older libraries read what they can.
    const std::uint32_t flags = flags_of(g) | (block.present ? kIsBlock : 0u);
    w.u32(version_for(flags));
    w.u32(static_cast<std::uint32_t>(geo.dim));
    w.u32(geo.axisymmetric ? 1u : 0u);
    w.i64(geo.nx);
    w.i64(geo.ny);
    w.f64(geo.dx);
    w.f64(geo.dy);
    w.f64(g.repose_angle());
    w.f64(g.mobility());
    w.f64(g.rest_tolerance());
    w.i64(g.max_substeps());
    w.i32(g.threads());
    w.u32(static_cast<std::uint32_t>(g.scheme()));
    for (int side = 0; side < 4; ++side) w.u8(g.side_open(side) ? 1 : 0);
    w.f64(g.flux_exponent());
    w.f64(g.static_angle());
    w.u32(flags_of(g) | (block.present ? kIsBlock : 0u));
    const MassLedger &ledger = g.ledger();
    for (const CompensatedSum *account : {&ledger.sourced, &ledger.external, &ledger.outflow, &ledger.unmet}) {
        w.f64(account->sum());
        w.f64(account->correction());
    }
    const StepInfo &info = g.last_step();
    w.i64(info.substeps);
    w.f64(info.time_integrated);
    w.u32(info.at_rest ? 1u : 0u);
    w.f64(info.max_excess_slope);
    w.f64(info.cell_updates);
    w.checksum();
}

void write_block(Writer &w, const RestartBlock &block) {
    if (!block.present) return;
    w.u64(block.save_mark);
    w.i64(block.global_nx);
    w.i64(block.global_ny);
    w.i64(block.i0);
    w.i64(block.j0);
    w.i32(block.rank);
    w.i32(block.ranks);
}

void write_mesh(Writer &w, const Grid &g) {
    if (!g.geometry().is_mesh()) return;
    const Mesh &mesh = *g.geometry().mesh;
    const MeshRecord r = record_of(mesh);
    w.u32(r.kind);
    w.u32(0);
    w.i64(r.nnodes);
    w.i64(r.ncells);
    w.i64(r.nindices);
    w.i64(r.nfaces);
    const MeshInput &in = mesh.input;
    if (in.kind == MeshInput::kGraph) {
        w.array(in.cell_xy, &Writer::f64);
        w.array(in.cell_area, &Writer::f64);
        w.array(in.face_cells, &Writer::i64);
        w.array(in.face_xy, &Writer::f64);
        w.array(in.face_length, &Writer::f64);
        return;
    }
    w.array(in.node_xy, &Writer::f64);
    w.array(in.cell_start, &Writer::i64);  // empty for the dual
    w.array(in.cell_nodes, &Writer::i64);
}

void write_part(Writer &w, const Grid &g) {
    if (!g.geometry().is_mesh() || g.geometry().mesh->input.owner.empty()) return;
    w.array(g.geometry().mesh->input.global_id, &Writer::i64);
    w.array(g.geometry().mesh->input.owner, &Writer::i32);
}

void write_body(Writer &w, const Grid &g) {
    w.array(g.heights(), &Writer::f64);
    w.array(g.residuals(), &Writer::f32);
    w.array(g.kinds(), &Writer::u8);
    w.array(g.source(), &Writer::f64);  // each optional array: nothing when empty
    w.array(g.bed(), &Writer::f64);
    w.array(g.angle_field(), &Writer::f64);
    w.array(g.moving(), &Writer::u8);
    if (flags_of(g) & kHasSideOutflows)
        for (const CompensatedSum &account : g.ledger().side_outflow) {
            w.f64(account.sum());
            w.f64(account.correction());
        }
    for (int side = 0; side < 4; ++side) w.array(g.side_levels(side), &Writer::f64);  // nothing when empty
    w.array(g.edge_open_flags(), &Writer::u8);                                          // nothing when empty
    w.checksum();
    w.flush();
}

// Closes a FILE on every path out, and removes the temporary file unless kept.
struct TempFile {
    std::FILE *file = nullptr;
    std::string path;
    bool keep = false;
    ~TempFile() {
        if (file) std::fclose(file);
        if (!keep) std::remove(path.c_str());
    }
};

// ---- reading ----------------------------------------------------------------

// Reads little-endian values from a byte range, refusing to run past its end.
class Reader {
public:
    Reader(const std::vector<std::uint8_t> &bytes, std::size_t at, const std::string &path, const char *function)
        : bytes_(bytes), at_(at), path_(path), function_(function) {}

    std::uint8_t u8() { return take(1)[0]; }
    std::uint32_t u32() {
        const std::uint8_t *p = take(4);
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(p[k]) << (8 * k);
        return v;
    }
    std::uint64_t u64() {
        const std::uint8_t *p = take(8);
        std::uint64_t v = 0;
        for (int k = 0; k < 8; ++k) v |= static_cast<std::uint64_t>(p[k]) << (8 * k);
        return v;
    }
    std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
    std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
    double f64() {
        const std::uint64_t bits = u64();
        double v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    float f32() {
        const std::uint32_t bits = u32();
        float v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    template <class T, class Get>
    void array(std::vector<T> &values, std::size_t n, Get get) {
        if (bytes_.size() - at_ < n)  // a cheap first guard; take() checks each value
            fail(DPSM_ERR_BAD_FILE, function_, path_, " is truncated inside its arrays");
        values.resize(n);
        for (std::size_t k = 0; k < n; ++k) values[k] = static_cast<T>((this->*get)());
    }
    std::size_t at() const { return at_; }

private:
    const std::uint8_t *take(std::size_t n) {
        if (bytes_.size() - at_ < n)
            fail(DPSM_ERR_BAD_FILE, function_, path_, " is truncated: a field at byte ", at_, " runs past its end");
        const std::uint8_t *p = bytes_.data() + at_;
        at_ += n;
        return p;
    }

    const std::vector<std::uint8_t> &bytes_;
    std::size_t at_;
    const std::string &path_;
    const char *function_;
};

// What the header says, before it is turned into a grid's state.
struct Header {
    MeshRecord mesh;  // kIsMesh only
    std::uint32_t version = 0, dim = 0, axisymmetric = 0;
    std::int64_t nx = 0, ny = 0;
    double dx = 0.0, dy = 0.0;
    std::uint32_t scheme = 0, flags = 0, at_rest = 0;
    std::array<std::uint8_t, 4> side_open{};
};

void read_header(Reader &r, Header &h, GridState &s) {
    for (std::size_t k = 0; k < kMagic.size(); ++k) r.u8();  // checked already
    h.version = r.u32();
    h.dim = r.u32();
    h.axisymmetric = r.u32();
    h.nx = r.i64();
    h.ny = r.i64();
    h.dx = r.f64();
    h.dy = r.f64();
    s.repose_angle = r.f64();
    s.mobility = r.f64();
    s.rest_tolerance = r.f64();
    s.max_substeps = r.i64();
    s.threads = r.i32();
    h.scheme = r.u32();
    for (std::uint8_t &open : h.side_open) open = r.u8();
    s.flux_exponent = r.f64();
    s.static_angle = r.f64();
    h.flags = r.u32();
    for (CompensatedSum *account : {&s.ledger.sourced, &s.ledger.external, &s.ledger.outflow, &s.ledger.unmet}) {
        const double sum = r.f64();
        const double correction = r.f64();
        *account = CompensatedSum(sum, correction);
    }
    s.last_step.substeps = r.i64();
    s.last_step.substeps_evaluated = s.last_step.substeps;  // not in the file
    s.last_step.time_integrated = r.f64();
    h.at_rest = r.u32();
    s.last_step.max_excess_slope = r.f64();
    s.last_step.cell_updates = r.f64();
    r.u32();  // the header's checksum, checked already
}

void read_block(Reader &r, const Header &h, RestartBlock &block) {
    block = RestartBlock{};
    if (!(h.flags & kIsBlock)) return;
    block.present = true;
    block.save_mark = r.u64();
    block.global_nx = r.i64();
    block.global_ny = r.i64();
    block.i0 = r.i64();
    block.j0 = r.i64();
    block.rank = r.i32();
    block.ranks = r.i32();
}

void read_body(Reader &r, const Header &h, std::size_t n, GridState &s) {
    r.array(s.heights, n, &Reader::f64);
    r.array(s.residuals, n, &Reader::f32);
    r.array(s.kinds, n, &Reader::u8);
    if (h.flags & kHasSource) r.array(s.source, n, &Reader::f64);
    if (h.flags & kHasBed) r.array(s.bed, n, &Reader::f64);
    if (h.flags & kHasAngleField) r.array(s.angle_field, n, &Reader::f64);
    if (h.flags & kHasMoving) r.array(s.moving, n, &Reader::u8);
    if (h.flags & kHasSideOutflows)
        for (CompensatedSum &account : s.ledger.side_outflow) {
            const double sum = r.f64();
            const double correction = r.f64();
            account = CompensatedSum(sum, correction);
        }
    for (int side = 0; side < 4; ++side)
        if (h.flags & side_levels_flag(side))
            r.array(s.side_levels[side], static_cast<std::size_t>(faces_along(side, h.nx, h.ny, h.mesh.nfaces)),
                    &Reader::f64);
    if (h.flags & kHasEdgeKinds) r.array(s.edge_open, static_cast<std::size_t>(h.mesh.nfaces), &Reader::u8);
}

void read_mesh_counts(Reader &r, Header &h) {
    if (!(h.flags & kIsMesh)) return;
    h.mesh.kind = r.u32();
    r.u32();
    h.mesh.nnodes = r.i64();
    h.mesh.ncells = r.i64();
    h.mesh.nindices = r.i64();
    h.mesh.nfaces = r.i64();
}

void read_mesh(Reader &r, const Header &h, MeshInput &in) {
    if (!(h.flags & kIsMesh)) return;
    const MeshRecord &m = h.mesh;
    const auto n = [](std::int64_t count) { return static_cast<std::size_t>(count); };
    in.kind = static_cast<MeshInput::Kind>(m.kind);
    if (m.kind == MeshInput::kGraph) {
        in.ncells = m.ncells;
        r.array(in.cell_xy, 2 * n(m.ncells), &Reader::f64);
        r.array(in.cell_area, n(m.ncells), &Reader::f64);
        r.array(in.face_cells, 2 * n(m.nfaces), &Reader::i64);
        r.array(in.face_xy, 2 * n(m.nfaces), &Reader::f64);
        r.array(in.face_length, n(m.nfaces), &Reader::f64);
        return;
    }
    r.array(in.node_xy, 2 * n(m.nnodes), &Reader::f64);
    if (m.kind == MeshInput::kPolygons) r.array(in.cell_start, n(m.ncells) + 1, &Reader::i64);
    r.array(in.cell_nodes, n(m.nindices), &Reader::i64);
}

// The bytes of version 4's parts after the arrays, by the flags (and a mesh's edge kinds).
std::size_t coupling_bytes(std::uint32_t flags, std::int64_t nx, std::int64_t ny, std::int64_t nfaces = 0) {
    std::size_t bytes = (flags & kHasSideOutflows) ? 4 * 16 : 0;
    for (int side = 0; side < 4; ++side)
        if (flags & side_levels_flag(side)) bytes += 8 * static_cast<std::size_t>(faces_along(side, nx, ny, nfaces));
    if (flags & kHasEdgeKinds) bytes += static_cast<std::size_t>(nfaces);
    return bytes;
}

// The bytes each cell takes in the body, by the arrays the flags announce.
std::size_t bytes_per_cell(std::uint32_t flags) {
    std::size_t bytes = 8 + 4 + 1;  // heights, residuals, kinds
    if (flags & kHasSource) bytes += 8;
    if (flags & kHasBed) bytes += 8;
    if (flags & kHasAngleField) bytes += 8;
    if (flags & kHasMoving) bytes += 1;
    return bytes;
}

bool is_angle(double theta) { return theta > 0.0 && theta < 0.5 * M_PI; }  // false for NaN
bool in_scale(double v) { return std::isfinite(v) && v >= 1.0 / kMaxMagnitude && v <= kMaxMagnitude; }
bool in_range(double v) { return std::isfinite(v) && std::fabs(v) <= kMaxMagnitude; }

std::string hex32(std::uint32_t v) {
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

// The header's sizes and layout: checked before the size of the file is
// compared with them and anything is allocated from them.
void check_layout(const Header &h, const std::string &path, const char *fn) {
    const auto bad = [&](const auto &...parts) { fail(DPSM_ERR_BAD_FILE, fn, path, ": ", parts...); };
    if (h.dim != 1 && h.dim != 2) bad("dim = ", h.dim, " is not 1 or 2");
    if (h.axisymmetric > 1) bad("axisymmetric = ", h.axisymmetric, " is not 0 or 1");
    if (h.axisymmetric && h.dim != 1) bad("an axisymmetric grid must have dim = 1, not ", h.dim);
    if (h.nx < 1) bad("nx = ", h.nx, " must be at least 1");
    if (h.ny < 1) bad("ny = ", h.ny, " must be at least 1");
    if (h.dim == 1 && h.ny != 1) bad("a 1D grid has ny = 1, not ", h.ny);
    if (h.nx > kMaxCells / h.ny)
        bad("nx * ny = ", h.nx, " * ", h.ny, " cells is more than this library can address (", kMaxCells, ")");
    if (h.flags & ~kKnownFlags) bad("unknown array flags ", hex32(h.flags & ~kKnownFlags));
    const std::pair<std::uint32_t, std::uint32_t> needs[] = {
        {kVersion2Flags, 2}, {kVersion3Flags, 3}, {kVersion4Flags, 4}, {kVersion5Flags, 5}, {kVersion6Flags, 6},
        {kVersion7Flags, 7}, {kVersion8Flags, 8}, {kVersion9Flags, 9}};
    for (const auto &[flags, version] : needs)
        if ((h.flags & flags) && h.version < version)
            bad("the flags ", hex32(h.flags & flags), " are set in a file of version ", h.version, " (they need version ",
                version, ")");
    const int relaxations = ((h.flags & kRelaxToRest) != 0) + ((h.flags & kRelaxAuto) != 0) + ((h.flags & kRelaxLocalSteps) != 0);
    if (relaxations > 1) bad(relaxations, " relaxation flags are set; a file holds at most one");
    if ((h.flags & kRelaxToRest) && h.dim != 2) bad("a grid of dim = ", h.dim, " cannot relax to rest");
    if ((h.flags & kIsBlock) && h.dim != 2) bad("a block of a distributed grid must have dim = 2, not ", h.dim);
    if ((h.flags & kHasEdgeKinds) && !(h.flags & kIsMesh)) bad("edge kinds are set but the file holds no mesh");
    if ((h.flags & kMeshPart) && !(h.flags & kIsMesh)) bad("a part of a distributed mesh is set but the file holds no mesh");
    if ((h.flags & kMeshGeographic) && !(h.flags & kIsMesh)) bad("geographic nodes are set but the file holds no mesh");
    if ((h.flags & kMeshFromOne) && !(h.flags & kIsMesh))
        bad("the mesh's indices are said to count from 1 but the file holds no mesh");
    if (h.flags & kIsMesh) {
        if (h.dim != 2 || h.ny != 1 || ((h.flags & kIsBlock) != 0) != ((h.flags & kMeshPart) != 0))
            bad("a mesh has dim = 2, ny = 1 and a block record only when it is a part of a distributed mesh");
        if (h.flags & (kHasSideLevels & ~side_levels_flag(kXMin))) bad("a mesh has levels beyond its edge only");
    }
    for (int side = 0; side < 4; ++side)
        if ((h.flags & side_levels_flag(side)) && ((h.dim == 1 && side >= kYMin) || (h.axisymmetric && side == kXMin)))
            bad("levels beyond side ", side, ", which a grid of dim = ", h.dim,
                h.axisymmetric ? " (axisymmetric)" : "", " does not have");
    const std::uint64_t cells = static_cast<std::uint64_t>(h.nx) * static_cast<std::uint64_t>(h.ny);
    if (cells > (std::numeric_limits<std::size_t>::max() - kHeaderBytes - kBlockBytes - kChecksumBytes -
                 coupling_bytes(h.flags, h.nx, h.ny)) /
                    bytes_per_cell(h.flags))
        bad(cells, " cells do not fit in this machine's memory");
}

// Every value as the setters would check it; the first one wrong is named.
void check_values(const Header &h, const GridState &s, std::size_t n, const std::string &path, const char *fn) {
    const auto bad = [&](const auto &...parts) { fail(DPSM_ERR_BAD_FILE, fn, path, ": ", parts...); };
    if (!in_scale(h.dx)) bad("dx = ", h.dx, " is outside the supported range [1e-50, 1e50]");
    if (h.dim == 2 ? !in_scale(h.dy) : h.dy != 1.0) bad("dy = ", h.dy, " is not valid for a grid of dim = ", h.dim);
    if (!is_angle(s.repose_angle)) bad("the angle of repose ", s.repose_angle, " radians is outside (0, pi/2)");
    if (!in_scale(s.mobility)) bad("the mobility ", s.mobility, " is outside the supported range [1e-50, 1e50]");
    if (!(std::isfinite(s.rest_tolerance) && s.rest_tolerance > 0.0))
        bad("the rest tolerance ", s.rest_tolerance, " is not finite and positive");
    if (s.max_substeps < 1) bad("the sub-step limit ", s.max_substeps, " must be at least 1");
    if (s.threads < 0) bad("threads = ", s.threads, " must be at least 0");
    if (h.scheme != kPairwise && h.scheme != kIsotropic) bad("scheme = ", h.scheme, " is not pairwise (0) or isotropic (1)");
    if (h.dim == 1 && h.scheme != kPairwise) bad("a 1D grid has the pairwise scheme (0), not ", h.scheme);
    for (int side = 0; side < 4; ++side) {
        if (h.side_open[side] > 1) bad("side ", side, " is ", static_cast<int>(h.side_open[side]), ", not 0 or 1");
        if (h.side_open[side] && h.dim == 1 && side >= kYMin) bad("a 1D grid has no open y side (side ", side, ")");
        if (h.side_open[side] && h.axisymmetric && side == kXMin) bad("the axis of an axisymmetric grid is open");
    }
    if (!(s.flux_exponent >= 1.0 && s.flux_exponent <= DPSM_MAX_FLUX_EXPONENT))
        bad("the flux exponent ", s.flux_exponent, " is outside [1, ", DPSM_MAX_FLUX_EXPONENT, "]");
    if (!(s.static_angle == 0.0 || is_angle(s.static_angle)))
        bad("the static angle ", s.static_angle, " radians is neither 0 (none) nor in (0, pi/2)");
    if (((h.flags & kHasMoving) != 0) != (s.static_angle > 0.0))
        bad("the moving cells are ", (h.flags & kHasMoving) ? "present" : "missing", " but the static angle is ",
            s.static_angle);
    const MassLedger &l = s.ledger;
    for (const CompensatedSum *account : {&l.sourced, &l.external, &l.outflow, &l.unmet, &l.side_outflow[0],
                                          &l.side_outflow[1], &l.side_outflow[2], &l.side_outflow[3]})
        if (!std::isfinite(account->sum()) || !std::isfinite(account->correction()))
            bad("a ledger account is not finite (", account->sum(), " + ", account->correction(), ")");
    for (int side = 0; side < 4; ++side)
        for (std::size_t k = 0; k < s.side_levels[side].size(); ++k)
            if (!in_range(s.side_levels[side][k]))
                bad("the level beyond face ", k, " of side ", side, " = ", s.side_levels[side][k],
                    " is not finite within [-1e50, 1e50]");
    const StepInfo &info = s.last_step;
    if (info.substeps < 0) bad("the last step's sub-steps ", info.substeps, " are negative");
    if (!(std::isfinite(info.time_integrated) && info.time_integrated >= 0.0))
        bad("the last step's time integrated ", info.time_integrated, " is not finite and non-negative");
    if (h.at_rest > 1) bad("the last step's at-rest flag is ", h.at_rest, ", not 0 or 1");
    if (!(std::isfinite(info.max_excess_slope) && info.max_excess_slope >= 0.0))
        bad("the last step's largest excess slope ", info.max_excess_slope, " is not finite and non-negative");
    if (!(std::isfinite(info.cell_updates) && info.cell_updates >= 0.0))
        bad("the last step's cell updates ", info.cell_updates, " are not finite and non-negative");

    const auto cell = [&](std::size_t c) {
        std::ostringstream where;
        where << "[" << c << "] (cell i = " << static_cast<std::int64_t>(c) % h.nx
              << ", j = " << static_cast<std::int64_t>(c) / h.nx << ")";
        return where.str();
    };
    for (std::size_t c = 0; c < n; ++c) {
        if (!in_range(s.heights[c])) bad("h", cell(c), " = ", s.heights[c], " is not finite within [-1e50, 1e50]");
        if (!std::isfinite(s.residuals[c])) bad("the rounding residual", cell(c), " is not finite");
        if (s.kinds[c] > kOpen) bad("kinds", cell(c), " = ", static_cast<int>(s.kinds[c]), " is not 0, 1 or 2");
        if (!s.source.empty() && !in_range(s.source[c]))
            bad("q", cell(c), " = ", s.source[c], " is not finite within [-1e50, 1e50]");
        if (!s.bed.empty()) {
            if (!in_range(s.bed[c])) bad("zb", cell(c), " = ", s.bed[c], " is not finite within [-1e50, 1e50]");
            if (s.heights[c] < s.bed[c]) bad("h", cell(c), " = ", s.heights[c], " lies below its bed ", s.bed[c]);
        }
        if (!s.angle_field.empty() && !is_angle(s.angle_field[c]))
            bad("theta", cell(c), " = ", s.angle_field[c], " radians is outside (0, pi/2)");
        if (!s.moving.empty() && s.moving[c] > 1)
            bad("moving", cell(c), " = ", static_cast<int>(s.moving[c]), " is not 0 or 1");
    }
}

// The block record against the block's own size: its place in the global grid.
void check_block(const Header &h, const RestartBlock &b, const std::string &path, const char *fn) {
    if (!b.present) return;
    const auto bad = [&](const auto &...parts) { fail(DPSM_ERR_BAD_FILE, fn, path, ": ", parts...); };
    if (b.ranks < 1) bad("the block record says ", b.ranks, " ranks; at least 1");
    if (b.rank < 0 || b.rank >= b.ranks) bad("the block record's rank ", b.rank, " is not one of its ", b.ranks, " ranks");
    if (b.global_nx < 1 || b.global_ny < 1 || b.global_nx > kMaxCells / b.global_ny)
        bad("the block record's global grid of ", b.global_nx, " x ", b.global_ny, " cells is not valid");
    if (b.i0 < 0 || b.j0 < 0 || b.i0 > b.global_nx - h.nx || b.j0 > b.global_ny - h.ny)
        bad("the block [", b.i0, ", ", b.i0 + h.nx, ") x [", b.j0, ", ", b.j0 + h.ny, ") does not lie in its global grid [0, ",
            b.global_nx, ") x [0, ", b.global_ny, ")");
}

// Reads up to `want` more bytes onto `bytes`; false at the end of the file.
bool read_more(std::FILE *file, std::vector<std::uint8_t> &bytes, std::size_t want, const std::string &path,
               const char *fn) {
    const std::size_t old = bytes.size();
    bytes.resize(old + want);
    const std::size_t got = std::fread(bytes.data() + old, 1, want, file);
    bytes.resize(old + got);
    if (got < want && std::ferror(file)) fail(DPSM_ERR_IO, fn, "cannot read ", path, ": ", system_reason(errno));
    return got == want;
}

}  // namespace

void save_restart(const Grid &grid, const char *path, const char *function, const RestartBlock &block) {
    const std::string target(path);
    TempFile tmp;
    tmp.path = target + ".tmp";
    errno = 0;
    tmp.file = std::fopen(tmp.path.c_str(), "wb");
    if (!tmp.file) {
        tmp.keep = true;  // not ours: it may be something that exists and is not a file
        fail(DPSM_ERR_IO, function, "cannot write ", target, ": cannot create ", tmp.path, ": ", system_reason(errno));
    }
    Writer w(tmp.file, target, function);
    write_header(w, grid, block);
    if (w.buffered() != kHeaderBytes)
        fail(DPSM_ERR_INTERNAL, function, "the header takes ", w.buffered(), " bytes, not ", kHeaderBytes);
    write_block(w, block);
    write_mesh(w, grid);
    write_part(w, grid);
    write_body(w, grid);
    // On disk before it replaces the old file: a crash leaves one or the other.
    if (std::fflush(tmp.file) != 0) fail(DPSM_ERR_IO, function, "cannot write ", target, ": ", system_reason(errno));
#if defined(__unix__) || defined(__APPLE__)
    if (fsync(fileno(tmp.file)) != 0) fail(DPSM_ERR_IO, function, "cannot write ", target, ": ", system_reason(errno));
#endif
    std::FILE *file = tmp.file;
    tmp.file = nullptr;
    if (std::fclose(file) != 0) fail(DPSM_ERR_IO, function, "cannot write ", target, ": ", system_reason(errno));
#if defined(_WIN32)
    std::remove(target.c_str());  // rename does not replace a file there
#endif
    if (std::rename(tmp.path.c_str(), target.c_str()) != 0)
        fail(DPSM_ERR_IO, function, "cannot write ", target, ": cannot rename ", tmp.path, " to it: ",
             system_reason(errno));
    tmp.keep = true;  // it is the target now
}

RestartBlock written_block(const char *path, const char *fn) {
    struct Closer {
        std::FILE *file;
        ~Closer() {
            if (file) std::fclose(file);
        }
    } in{std::fopen(path, "rb")};
    const std::string source(path);
    if (!in.file) fail(DPSM_ERR_IO, fn, "cannot read back ", source, ": ", system_reason(errno));
    std::vector<std::uint8_t> bytes;
    RestartBlock block;
    if (!read_more(in.file, bytes, kHeaderBytes + kBlockBytes, source, fn)) return block;
    Header header;
    GridState ignored;
    Reader r(bytes, 0, source, fn);
    read_header(r, header, ignored);
    read_block(r, header, block);
    return block;
}

void load_restart(const char *path, Geometry &geometry, GridState &state, RestartBlock &block, const char *fn) {
    const std::string source(path);
    errno = 0;
    struct Closer {
        std::FILE *file;
        ~Closer() {
            if (file) std::fclose(file);
        }
    } in{std::fopen(path, "rb")};
    if (!in.file) fail(DPSM_ERR_IO, fn, "cannot open ", source, ": ", system_reason(errno));
    const auto bad = [&](const auto &...parts) { fail(DPSM_ERR_BAD_FILE, fn, source, parts...); };

    // The fixed header first: its checksum makes its sizes trustworthy.
    std::vector<std::uint8_t> bytes;
    read_more(in.file, bytes, kHeaderBytes, source, fn);
    const std::size_t got = bytes.size();
    if (got == 0) bad(" is empty, not a dpsm restart file");
    if (std::memcmp(bytes.data(), kMagic.data(), got < kMagic.size() ? got : kMagic.size()) != 0)
        bad(" is not a dpsm restart file (it does not begin with the dpsm restart signature)");
    if (got < 12) bad(" is truncated: expected at least ", kHeaderBytes, " bytes, found ", got);
    Header header;
    Reader r(bytes, 0, source, fn);
    for (std::size_t k = 0; k < kMagic.size(); ++k) r.u8();
    header.version = r.u32();
    if (header.version > kRestartVersion)
        bad(" was written by a newer dpsm, version ", header.version, " of the format; this library reads versions 1 to ",
            kRestartVersion);
    if (header.version == 0) bad(" is corrupted: format version 0 does not exist");
    if (got < kHeaderBytes) bad(" is truncated: expected at least ", kHeaderBytes, " bytes, found ", got);
    Reader checksum_reader(bytes, kHeaderBytes - kChecksumBytes, source, fn);
    const std::uint32_t stored_header = checksum_reader.u32();
    const std::uint32_t computed_header = crc32_update(0, bytes.data(), kHeaderBytes - kChecksumBytes);
    if (stored_header != computed_header)
        bad(" is corrupted: checksum mismatch in its header (stored ", hex32(stored_header), ", computed ",
            hex32(computed_header), ")");
    Reader header_reader(bytes, 0, source, fn);
    read_header(header_reader, header, state);
    check_layout(header, source, fn);

    // A mesh's counts next: they size the rest. Trusted only as far as they
    // are plausible; the file's checksum covers them.
    std::size_t mesh_bytes = 0;
    const std::size_t block_bytes = (header.flags & kIsBlock) ? kBlockBytes : 0;
    if (header.flags & kIsMesh) {
        read_more(in.file, bytes, block_bytes + kMeshRecordBytes, source, fn);
        if (bytes.size() < kHeaderBytes + block_bytes + kMeshRecordBytes)
            bad(" is truncated: its mesh record is cut short at ", bytes.size(), " bytes");
        Reader counts(bytes, kHeaderBytes + block_bytes, source, fn);
        read_mesh_counts(counts, header);
        const MeshRecord &m = header.mesh;
        const bool graph = m.kind == MeshInput::kGraph;
        if (m.kind != MeshInput::kPolygons && m.kind != MeshInput::kGraph && m.kind != MeshInput::kDual)
            bad(" is corrupted: mesh kind ", m.kind, " is not 1, 2 or 3");
        const std::int64_t most = kMaxCells / 8;
        if (m.nfaces < 1 || m.nfaces > most || m.ncells < 1 || m.ncells > most || m.nnodes < 0 || m.nnodes > most ||
            m.nindices < 0 || m.nindices > most || (graph ? m.ncells != header.nx : m.nnodes < 1))
            bad(" is corrupted: its mesh record's counts (", m.nnodes, " nodes, ", m.ncells, " cells, ", m.nindices,
                " node indices, ", m.nfaces, " faces) do not describe a mesh of ", header.nx, " cells");
        mesh_bytes = kMeshRecordBytes + m.array_bytes();
        if (header.flags & kMeshPart) mesh_bytes += static_cast<std::size_t>(header.nx) * (8 + 4);
    }
    // Then exactly as many bytes as the header implies, read as they come (a
    // short file allocates no more than it holds).
    const std::size_t n = static_cast<std::size_t>(header.nx) * static_cast<std::size_t>(header.ny);
    const std::size_t expected = kHeaderBytes + block_bytes + mesh_bytes + n * bytes_per_cell(header.flags) +
                                 coupling_bytes(header.flags, header.nx, header.ny, header.mesh.nfaces) + kChecksumBytes;
    constexpr std::size_t kChunk = std::size_t{1} << 22;
    while (bytes.size() <= expected) {
        const std::size_t want = expected + 1 - bytes.size();
        if (!read_more(in.file, bytes, want < kChunk ? want : kChunk, source, fn)) break;
    }
    if (bytes.size() < expected)
        bad(" is truncated: expected ", expected, " bytes, found ", bytes.size());
    if (bytes.size() > expected) {
        std::size_t found = bytes.size();
        std::vector<std::uint8_t> rest;
        while (read_more(in.file, rest, kChunk, source, fn)) {
            found += rest.size();
            rest.clear();
        }
        found += rest.size();
        bad(" is corrupted: expected ", expected, " bytes, found ", found, " (data after the end)");
    }
    Reader trailer(bytes, expected - kChecksumBytes, source, fn);
    const std::uint32_t stored = trailer.u32();
    const std::uint32_t computed = crc32_update(0, bytes.data(), expected - kChecksumBytes);
    if (stored != computed)
        bad(" is corrupted: checksum mismatch (stored ", hex32(stored), ", computed ", hex32(computed), ")");

    Reader body(bytes, kHeaderBytes, source, fn);
    read_block(body, header, block);
    MeshInput mesh_input;
    if (header.flags & kIsMesh) {
        read_mesh_counts(body, header);
        read_mesh(body, header, mesh_input);
        mesh_input.start_index = (header.flags & kMeshFromOne) ? 1 : 0;
        mesh_input.geographic = (header.flags & kMeshGeographic) != 0;
        if (header.flags & kMeshPart) {
            body.array(mesh_input.global_id, static_cast<std::size_t>(header.nx), &Reader::i64);
            body.array(mesh_input.owner, static_cast<std::size_t>(header.nx), &Reader::i32);
        }
    }
    read_body(body, header, n, state);
    if (body.at() != expected - kChecksumBytes)
        fail(DPSM_ERR_INTERNAL, fn, "read ", body.at(), " bytes of ", source, ", expected ", expected - kChecksumBytes);
    check_values(header, state, n, source, fn);
    check_block(header, block, source, fn);
    state.scheme = header.scheme == kIsotropic ? kIsotropic : kPairwise;
    state.relaxation = (header.flags & kRelaxToRest)       ? kToRest
                       : (header.flags & kRelaxAuto)       ? kAutoRelaxation
                       : (header.flags & kRelaxLocalSteps) ? kLocalSteps
                                                           : kTimeAccurate;
    state.last_step.at_rest = header.at_rest != 0;
    state.record_fluxes = (header.flags & kRecordsFluxes) != 0;
    for (int side = 0; side < 4; ++side) state.side_open[side] = header.side_open[side] != 0;
    geometry = Geometry{static_cast<int>(header.dim), header.axisymmetric != 0, header.nx, header.ny, header.dx, header.dy, nullptr};
    if (header.flags & kIsMesh) {
        // The same checks as the constructors; what they refuse, the file got wrong.
        for (std::size_t c = 0; c < mesh_input.owner.size(); ++c)
            if (mesh_input.global_id[c] < 0 || mesh_input.global_id[c] >= block.global_nx ||
                mesh_input.owner[c] < 0 || mesh_input.owner[c] >= block.ranks)
                bad(" is corrupted: local cell ", c, " has global id ", mesh_input.global_id[c], " and owner ",
                    mesh_input.owner[c], " in a mesh of ", block.global_nx, " cells on ", block.ranks, " ranks");
        try {
            if (header.flags & kMeshPart) {
                block.part = part_from_input(mesh_input, block.rank, fn);
                geometry.mesh = block.part;
            } else {
                geometry.mesh = mesh_from_input(mesh_input, fn);
            }
        } catch (const Error &e) {
            bad(" holds a mesh its constructor refuses: ", e.what());
        }
        if (geometry.mesh->cells != header.nx || geometry.mesh->faces != header.mesh.nfaces)
            bad(" is corrupted: its mesh has ", geometry.mesh->cells, " cells and ", geometry.mesh->faces,
                " faces, its header says ", header.nx, " and ", header.mesh.nfaces);
        geometry.dx = geometry.dy = geometry.mesh->min_distance;
        for (std::uint8_t &open : state.edge_open) open = open != 0;
    }
}

}  // namespace dpsm
