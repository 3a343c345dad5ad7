// hybrid's caster masks on the GPU (ours; twin: hybrid's cpu/casters.rs): each small
// piece of the z-fail volumes (one connected component's, closed by itself) is counted only at the
// silhouette pixels inside its shaft (hybrid::shafts), by compute passes instead of the rasterizer.
// Follows shadow_map.wgsl (for g_position and cube_face) and the listed pixels' declarations
// (CASTER_LISTS in shaders.rs), which the mask pass appends to.
//
// The tables these passes only read (the triangles, their setups, the shafts and the shaft grid) are
// textures: lavapipe fetches a texel several times faster than it loads from a storage buffer.
//
// The passes: cs_setup sets each triangle up for the view; cs_tally finds each listed pixel's pieces
// (those of its light-space grid cell whose shafts hold it) and counts the pixels of each piece;
// cs_offsets gives each piece its run of pairs; cs_fill writes them; cs_pieces counts each piece at its
// pixels, a workgroup per piece (its invocations read one triangle at a time, the same for all); cs_alone
// counts the pixels whose pairs did not fit, every piece of theirs, as one invocation per pixel. A
// workgroup per piece rather than an invocation per pixel: the invocations then read the same triangle
// at once instead of each its own pieces' (on tree a third faster on lavapipe; cubes alike).
//
// The count at a pixel is the rasterizer's, taken by homogeneous rasterization (Olano and Greer 1997): a
// triangle with clip-space corners a, b, c (columns of M, in x, y, w) covers the pixel at NDC point p
// where the three rows of adj(M) = (b x c, c x a, a x b) dotted with (p, 1) all have the sign of det(M):
// the point of the triangle seen there is in front of the eye, corners at infinity (w = 0) and behind it
// included, with no clipping; its facing is det(M)'s sign, and its depth there (z . adj(M) p) / det(M),
// used only to leave out what the near plane clips. Whether a side lies behind the receiver is not read
// from that depth, which loses most of its digits to cancellation where a side meets the receiver (at
// the shadow's edge, on tree, hundreds of pixels would fall on the wrong side), but from the
// side's plane in world space: the eye ray meets it behind the receiver's G-buffer position exactly
// where the eye and that position lie on one side of it.
// Watertight: two triangles sharing an edge compute its row from the same two corners in one order (the
// lesser first, see `edge_row`), so they get exactly opposite values at every pixel, and a pixel exactly
// on it goes to the side its row's gradient points to along x (y where x is 0): as if every pixel were
// moved by the same infinitesimal step, each is covered exactly once by triangles that tile around it.

struct CasterParams {
    // Per projection: world to the light's view (hybrid::shafts::light_coords).
    view_from_world: array<mat4x4<f32>, 6>,
    // Per projection: the grid's origin (xy) and cells per light-space unit (zw).
    grid: array<vec4<f32>, 6>,
    // Per projection: x the grid's side in cells, y its first cell in `grid_texels`, z 1 if orthographic.
    cells: array<vec4<u32>, 6>,
    // x: 1 for a point light (cube faces), y: projections, z: pieces, w: triangles.
    counts: vec4<u32>,
    // xyz: the light's position (point lights); w: the camera's near plane.
    light: vec4<f32>,
    // x: where the piece lists start in `grid_texels`.
    lists: vec4<u32>,
};

// A piece's run of triangles: from `first`, `sides` sides, then `caps` near caps and as many far caps;
// `quads` 1 where the sides come in quads (two triangles each: every light but a directional one).
struct PieceRun {
    first: u32,
    sides: u32,
    caps: u32,
    quads: u32,
};

@group(1) @binding(9) var<storage, read_write> counts: array<atomic<i32>>;
@group(1) @binding(11) var<uniform> casters: CasterParams;
// Per triangle four texels: its corners as homogeneous points in its mesh's space, wound so its front
// face is counter-clockwise (their bits), then x: instance * 2 + 1 for a cap (near or far), + 0 for a
// side; y: its piece; z: its group (0 side, 1 near cap, 2 far cap). A table (TABLE_ROW texels a row),
// fetched faster than a storage buffer is read on lavapipe.
@group(1) @binding(12) var triangle_texels: texture_2d<u32>;

fn triangle_at(i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(textureLoad(triangle_texels, table_at(i), 0));
}

// Per triangle SETUP vec4, set up for the view: the rows of adj(M) with det(M) in the first's w, the depth
// row (z . adj(M)) with the cap flag in w, and the world plane through the triangle, turned so the eye
// lies on its positive side.
@group(1) @binding(13) var<storage, read_write> setups: array<vec4<f32>>;
// The same, copied into a texture (TABLE_ROW texels a row) after cs_setup, for the passes that read them:
// lavapipe (Mesa 22.3) loads from a storage buffer lane by lane and fetches texels a quad at a time, so
// reading the setups from the texture makes cs_pieces two to three times faster there.
@group(1) @binding(17) var setup_texels: texture_2d<f32>;

// Per piece, per projection, the shaft as `holds` reads it, in three texels: its least and greatest
// outline (lo, hi), then x its near distance and y 1 where it is bounded (0: the piece reaches the
// light's plane and may shadow any pixel of the projection).
@group(1) @binding(18) var shaft_texels: texture_2d<f32>;
// Per cell of every projection's grid, where its pieces start (and one more), then the piece lists.
@group(1) @binding(15) var grid_texels: texture_2d<u32>;

// Where element `i` of a table laid out in a texture, TABLE_ROW texels a row, is.
fn table_at(i: u32) -> vec2<u32> {
    return vec2<u32>(i % TABLE_ROW, i / TABLE_ROW);
}

const TABLE_ROW: u32 = 4096u;

fn setup_at(i: u32) -> vec4<f32> {
    return textureLoad(setup_texels, table_at(i), 0);
}

// Per instance of the frame, its world_from_local, a column a texel (the frame's `instances` hold the same,
// but in a storage buffer, which lavapipe loads lane by lane: 16 loads per triangle set up).
@group(1) @binding(19) var instance_texels: texture_2d<f32>;

fn instance_at(i: u32) -> mat4x4<f32> {
    return mat4x4<f32>(
        textureLoad(instance_texels, table_at(4u * i), 0),
        textureLoad(instance_texels, table_at(4u * i + 1u), 0),
        textureLoad(instance_texels, table_at(4u * i + 2u), 0),
        textureLoad(instance_texels, table_at(4u * i + 3u), 0),
    );
}

fn grid_at(i: u32) -> u32 {
    return textureLoad(grid_texels, table_at(i), 0).x;
}

// Per piece.
@group(1) @binding(14) var<storage, read> runs: array<PieceRun>;

const GROUP: u32 = 64u;
const SETUP: u32 = 5u;

// The invocation's index over a dispatch of (x, y) workgroups of GROUP (y > 1 past 65 535 groups).
fn invocation(wg: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (wg.y * groups.x + wg.x) * GROUP + local;
}

// The homogeneous line through u and v, computed with the lesser corner first so that the edge's two
// triangles get exact negatives of each other.
fn edge_row(u: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let u_first = u.x < v.x || (u.x == v.x && (u.y < v.y || (u.y == v.y && u.z < v.z)));
    if (u_first) {
        return cross(u, v);
    }
    return -cross(v, u);
}

// The plane through three homogeneous points (x, y, z, w): each component the cofactor of a 4 x 4
// determinant with the points as rows, so the plane's dot product with each of them is 0.
fn plane_through(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(
        dot(a.yzw, cross(b.yzw, c.yzw)),
        -dot(a.xzw, cross(b.xzw, c.xzw)),
        dot(a.xyw, cross(b.xyw, c.xyw)),
        -dot(a.xyz, cross(b.xyz, c.xyz)),
    );
}

@compute @workgroup_size(64)
fn cs_setup(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let t = invocation(wg, groups, local);
    if (t >= casters.counts.w) {
        return;
    }
    let about = textureLoad(triangle_texels, table_at(4u * t + 3u), 0);
    let info = about.x;
    let world_from_local = instance_at(info >> 1u);
    let wa = world_from_local * triangle_at(4u * t);
    let wb = world_from_local * triangle_at(4u * t + 1u);
    let wc = world_from_local * triangle_at(4u * t + 2u);
    // clip_position's own product, so that corners shared by triangles agree to the bit.
    let a = view.clip_from_world * wa;
    let b = view.clip_from_world * wb;
    let c = view.clip_from_world * wc;
    let e0 = edge_row(b.xyw, c.xyw);
    let e1 = edge_row(c.xyw, a.xyw);
    let e2 = edge_row(a.xyw, b.xyw);
    let plane = plane_through(wa, wb, wc);
    let eye_side = dot(plane, vec4<f32>(view.eye.xyz, 1.0));
    setups[SETUP * t] = vec4<f32>(e0, dot(a.xyw, e0));
    setups[SETUP * t + 1u] = vec4<f32>(e1, 0.0);
    setups[SETUP * t + 2u] = vec4<f32>(e2, 0.0);
    setups[SETUP * t + 3u] = vec4<f32>(a.z * e0 + b.z * e1 + c.z * e2, f32(info & 1u));
    setups[SETUP * t + 4u] = select(plane, -plane, eye_side < 0.0);
    let group = about.z;
    if (group != 0u) {
        widen_bounds(PIECE * about.y + 3u + 4u * (group - 1u), a, b, c);
    }
}

// A float's bits in an order atomicMax keeps: negatives below positives, each in its own order.
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// Adds a triangle with clip-space corners a, b, c to the screen bounds at `at` in the work buffer: four
// words, ~ordered(least x), ~ordered(least y), ordered(greatest x), ordered(greatest y), so that all four
// grow by atomicMax and 0 (cleared) is empty. A corner at or behind the eye's plane makes them the whole
// plane: the triangle's picture is then not within its corners'.
fn widen_bounds(at: u32, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) {
    var lo = vec2<f32>(-3.0e38);
    var hi = vec2<f32>(3.0e38);
    if (a.w > 0.0 && b.w > 0.0 && c.w > 0.0) {
        let pa = a.xy / a.w;
        let pb = b.xy / b.w;
        let pc = c.xy / c.w;
        lo = min(pa, min(pb, pc));
        hi = max(pa, max(pb, pc));
    }
    atomicMax(&work[at], ~ordered(lo.x));
    atomicMax(&work[at + 1u], ~ordered(lo.y));
    atomicMax(&work[at + 2u], ordered(hi.x));
    atomicMax(&work[at + 3u], ordered(hi.y));
}

// Whether NDC point `p` lies within the bounds at `at` (widened for rounding).
fn within_bounds(at: u32, p: vec3<f32>) -> bool {
    let lo = vec2<f32>(unordered(~atomicLoad(&work[at])), unordered(~atomicLoad(&work[at + 1u])));
    let hi = vec2<f32>(unordered(atomicLoad(&work[at + 2u])), unordered(atomicLoad(&work[at + 3u])));
    let margin = 1.0e-4 * (1.0 + max(abs(lo), abs(hi)));
    return all(p.xy >= lo - margin) && all(p.xy <= hi + margin);
}

// Whether an edge's oriented value `e` at the pixel covers it, ties going by the row's gradient `r`.
fn inside(e: f32, r: vec3<f32>) -> bool {
    return e > 0.0 || (e == 0.0 && (r.x > 0.0 || (r.x == 0.0 && r.y > 0.0)));
}

// What one piece adds at a pixel: the count, the fragments the rasterizer would make there, and the
// stencil updates (z-fail's: where the depth test fails).
struct Tally {
    count: i32,
    fragments: u32,
    updates: u32,
    tests: u32,
};

// Whether the edge row at `i` in the setups, oriented by `o`, covers NDC point `p`.
fn covers(i: u32, o: f32, p: vec3<f32>) -> bool {
    let e = setup_at(i).xyz * o;
    return inside(dot(e, p), e);
}

// The fragment of triangle `t` (or of the side quad it begins), of orientation `o`, at a pixel it
// covers at NDC point `p`, over the receiver at world position `receiver`: made unless the near plane
// clips it there, and counted the z-fail way, adding 1 for a back face and -1 for a front face where it
// lies behind the receiver (or at it: `Less` fails). Caps always count: a near cap is the caster's own
// surface, never in front of the receiver but at it only up to rounding, and a far cap is at infinity.
fn add_fragment(t: u32, o: f32, p: vec3<f32>, receiver: vec4<f32>, tally: ptr<function, Tally>) {
    let zr = setup_at(SETUP * t + 3u);
    if (dot(zr.xyz, p) * o < 0.0) {
        return;
    }
    (*tally).fragments += 1u;
    if (zr.w != 0.0 || dot(setup_at(SETUP * t + 4u), receiver) >= 0.0) {
        (*tally).count += select(1, -1, o > 0.0);
        (*tally).updates += 1u;
    }
}

// Triangles `first` to `end` at NDC point `p` over the receiver at world position `receiver`, each edge
// read and tested in turn (most triangles fail the first or second).
fn add_triangles(first: u32, end: u32, p: vec3<f32>, receiver: vec4<f32>, tally: ptr<function, Tally>) {
    (*tally).tests += end - first;
    for (var t = first; t < end; t++) {
        let i = SETUP * t;
        let det = setup_at(i).w;
        let o = select(-1.0, 1.0, det > 0.0);
        if (det != 0.0 && covers(i, o, p) && covers(i + 1u, o, p) && covers(i + 2u, o, p)) {
            add_fragment(t, o, p, receiver, tally);
        }
    }
}

// Side quads `first` to `end` (two triangles each, sharing a diagonal), as add_triangles. A side quad is
// planar and convex (the part of a wedge from the light beyond a silhouette edge), so a pixel is covered
// by one of its triangles exactly where the quad's four edges all cover it: as for a triangle, the
// homogeneous test holds for any convex planar polygon, since a point cannot lie outside all of its
// edges at once. Its two triangles share their plane, their facing, their depth row and their world
// plane, so one test of four edges does the work of two of three: the upload turns each side triangle so
// that the diagonal is its second row (Split::write_piece), and the quad's four edges are the first and
// third rows of each. Each quad counts as its two triangles tested.
fn add_quads(first: u32, end: u32, p: vec3<f32>, receiver: vec4<f32>, tally: ptr<function, Tally>) {
    (*tally).tests += end - first;
    for (var t = first; t < end; t += 2u) {
        let i = SETUP * t;
        let j = i + SETUP;
        let det = setup_at(i).w;
        let o = select(-1.0, 1.0, det > 0.0);
        if (det != 0.0 && covers(i, o, p) && covers(i + 2u, o, p) && covers(j, o, p) && covers(j + 2u, o, p)) {
            add_fragment(t, o, p, receiver, tally);
        }
    }
}

// Piece `k` at NDC point `p` over the receiver at world position `receiver`: its sides, and its near and
// far caps where their bounds on screen hold the pixel (a twig's caps are a few pixels across, its sides
// reach its shadow).
fn add_piece(k: u32, p: vec3<f32>, receiver: vec4<f32>, tally: ptr<function, Tally>) {
    let s = runs[k];
    let near = s.first + s.sides;
    let far = near + s.caps;
    if (s.quads != 0u) {
        add_quads(s.first, near, p, receiver, tally);
    } else {
        add_triangles(s.first, near, p, receiver, tally);
    }
    if (within_bounds(PIECE * k + 3u, p)) {
        add_triangles(near, far, p, receiver, tally);
    }
    if (within_bounds(PIECE * k + 7u, p)) {
        add_triangles(far, far + s.caps, p, receiver, tally);
    }
}

// Twin: hybrid::shafts::tolerance.
fn tolerance(r: f32, near: f32) -> f32 {
    return r * (1.0 / 4096.0) + r * r / near * (1.0 / 262144.0);
}

// Twin: hybrid::shafts::Shaft::holds, for the shaft lo, hi, near and a point with outline `o`,
// distance `d` and tolerances.
fn holds(lo: vec4<f32>, hi: vec4<f32>, near: f32, o: vec4<f32>, d: f32, side: f32, along: f32) -> bool {
    let tol = vec4<f32>(side, side, 2.0 * side, 2.0 * side);
    return d >= near - along && all(o >= lo - tol) && all(o <= hi + tol);
}

// Where a listed pixel's candidate pieces are: the pieces of its light-space cell (entries `first` to
// `end` of the cell lists), each kept where its shaft holds the pixel, or every piece (`all`) where the
// pixel lies at or behind a perspective light's plane.
struct Candidates {
    first: u32,
    end: u32,
    all: bool,
    projection: u32,
    o: vec4<f32>,
    d: f32,
    side: f32,
    along: f32,
};

const NONE: u32 = 0xffffffffu;

// A listed pixel's world position and its NDC point (its centre).
fn pixel_position(at: u32) -> vec3<f32> {
    let width = u32(view.size.x);
    return textureLoad(g_position, vec2<u32>(at % width, at / width), 0).xyz;
}

fn pixel_ndc(at: u32) -> vec3<f32> {
    let width = u32(view.size.x);
    let px = vec2<f32>(f32(at % width), f32(at / width)) + 0.5;
    return vec3<f32>(px.x * 2.0 * view.size.z - 1.0, 1.0 - px.y * 2.0 * view.size.w, 1.0);
}

fn candidates(pos: vec3<f32>) -> Candidates {
    var j = 0u;
    if (casters.counts.x == 1u) {
        j = u32(cube_face(pos - casters.light.xyz));
    }
    let v = casters.view_from_world[j] * vec4<f32>(pos, 1.0);
    let d = -v.z;
    let orthographic = casters.cells[j].z == 1u;
    if (!orthographic && d <= 0.0) {
        return Candidates(0u, casters.counts.z, true, j, vec4<f32>(0.0), d, 0.0, 0.0);
    }
    let xy = select(v.xy / d, v.xy, orthographic);
    let tol = tolerance(distance(pos, view.eye.xyz), casters.light.w);
    let side = select(2.0 * tol / d, 2.0 * tol, orthographic);
    let g = casters.grid[j];
    let n = i32(casters.cells[j].x);
    let cell = clamp(vec2<i32>(floor((xy - g.xy) * g.zw)), vec2<i32>(0), vec2<i32>(n - 1));
    let c = casters.cells[j].y + u32(cell.y * n + cell.x);
    let o = vec4<f32>(xy, xy.x + xy.y, xy.x - xy.y);
    return Candidates(grid_at(c), grid_at(c + 1u), false, j, o, d, side, tol);
}

// Entry `e` of a pixel's candidates: the piece, or NONE where its shaft does not hold the pixel.
fn candidate(c: Candidates, e: u32) -> u32 {
    if (c.all) {
        return e;
    }
    let k = grid_at(casters.lists.x + e);
    let at = 3u * (k * casters.counts.y + c.projection);
    let near = textureLoad(shaft_texels, table_at(at + 2u), 0).xy;
    if (near.y == 0.0) {
        return k;
    }
    let lo = textureLoad(shaft_texels, table_at(at), 0);
    let hi = textureLoad(shaft_texels, table_at(at + 1u), 0);
    if (holds(lo, hi, near.x, c.o, c.d, c.side, c.along)) {
        return k;
    }
    return NONE;
}

// The work buffer: per piece its pixel count, its first pair, its cursor and the screen bounds of its
// near caps and of its far caps (`widen_bounds`; PIECE words in all), the number of staged pairs, then per
// listed pixel a flag (1: too many pairs, the pixel counts every piece itself), then the pairs, each a
// listed pixel's index, a run per piece, then the staged pairs (a listed pixel's index and a piece, in the
// order the tally found them, twice the pairs' room).
@group(1) @binding(16) var<storage, read_write> work: array<atomic<u32>>;

const PIECE: u32 = 11u;

fn staged_count() -> u32 {
    return PIECE * casters.counts.z;
}

fn flags_start() -> u32 {
    return staged_count() + 1u;
}

fn pairs_start() -> u32 {
    return flags_start() + u32(view.size.x) * u32(view.size.y);
}

// How many pairs the work buffer has room for (and staged pairs).
fn pair_room() -> u32 {
    return (arrayLength(&work) - pairs_start()) / 3u;
}

fn staging_start() -> u32 {
    return pairs_start() + pair_room();
}

// Pass 1, per listed pixel: its count set to 0, its flag cleared, and each pair of it and a candidate
// staged and counted in the candidate's pixels; a pixel with a pair past the room is flagged and counts
// every piece itself (pass 5). The pairs are found once: pass 3 only moves them into their runs.
@compute @workgroup_size(64)
fn cs_tally(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = atomicLoad(&listed.pixels);
    let room = pair_room();
    for (var i = invocation(wg, groups, local); i < n; i += groups.x * groups.y * GROUP) {
        let at = listed.at[i];
        atomicStore(&counts[at], 0);
        var flag = 0u;
        let c = candidates(pixel_position(at));
        for (var e = c.first; e < c.end; e++) {
            let k = candidate(c, e);
            if (k == NONE) {
                continue;
            }
            let s = atomicAdd(&work[staged_count()], 1u);
            if (s < room) {
                atomicStore(&work[staging_start() + 2u * s], i);
                atomicStore(&work[staging_start() + 2u * s + 1u], k);
                atomicAdd(&work[PIECE * k], 1u);
            } else {
                flag = 1u;
            }
        }
        atomicStore(&work[flags_start() + i], flag);
        if (flag != 0u) {
            atomicAdd(&listed.alone, 1u);
        }
    }
}

var<workgroup> sums: array<u32, 256>;

// Pass 2, one workgroup of 256: each piece's first pair and cursor, by a prefix sum of the counts.
@compute @workgroup_size(256)
fn cs_offsets(@builtin(local_invocation_index) local: u32) {
    let pieces = casters.counts.z;
    let chunk = (pieces + 255u) / 256u;
    let lo = min(local * chunk, pieces);
    let hi = min(lo + chunk, pieces);
    var total = 0u;
    for (var k = lo; k < hi; k++) {
        total += atomicLoad(&work[PIECE * k]);
    }
    sums[local] = total;
    workgroupBarrier();
    // Hillis-Steele, inclusive.
    for (var step = 1u; step < 256u; step *= 2u) {
        var add = 0u;
        if (local >= step) {
            add = sums[local - step];
        }
        workgroupBarrier();
        sums[local] += add;
        workgroupBarrier();
    }
    var start = sums[local] - total;
    for (var k = lo; k < hi; k++) {
        atomicStore(&work[PIECE * k + 1u], start);
        atomicStore(&work[PIECE * k + 2u], start);
        start += atomicLoad(&work[PIECE * k]);
    }
}

// Pass 3, per staged pair: the pixel written into its piece's run.
@compute @workgroup_size(64)
fn cs_fill(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = min(atomicLoad(&work[staged_count()]), pair_room());
    for (var s = invocation(wg, groups, local); s < n; s += groups.x * groups.y * GROUP) {
        let i = atomicLoad(&work[staging_start() + 2u * s]);
        let k = atomicLoad(&work[staging_start() + 2u * s + 1u]);
        let slot = atomicAdd(&work[PIECE * k + 2u], 1u);
        atomicStore(&work[pairs_start() + slot], i);
    }
}

// Adds a tally's count to a pixel and its work to the counters.
fn settle(at: u32, tally: Tally) {
    if (tally.count != 0) {
        atomicAdd(&counts[at], tally.count);
    }
    if (tally.tests > 0u) {
        atomicAdd(&listed.fragments, tally.fragments);
        atomicAdd(&listed.updates, tally.updates);
        atomicAdd(&listed.tests, tally.tests);
    }
}

// Pass 4, a workgroup per piece: the piece counted at each of its pixels, the invocations going through
// its pixels together, so they read the same triangle at the same time.
@compute @workgroup_size(64)
fn cs_pieces(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = wg.y * groups.x + wg.x;
    if (k >= casters.counts.z) {
        return;
    }
    let first = atomicLoad(&work[PIECE * k + 1u]);
    let end = min(first + atomicLoad(&work[PIECE * k]), pair_room());
    for (var slot = first + local; slot < end; slot += GROUP) {
        let i = atomicLoad(&work[pairs_start() + slot]);
        if (atomicLoad(&work[flags_start() + i]) != 0u) {
            continue;
        }
        let at = listed.at[i];
        var tally = Tally(0, 0u, 0u, 0u);
        add_piece(k, pixel_ndc(at), vec4<f32>(pixel_position(at), 1.0), &tally);
        settle(at, tally);
    }
}

// Pass 5, per flagged pixel: every candidate counted there.
@compute @workgroup_size(64)
fn cs_alone(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    // Usually no pixel is flagged: then no flag is read.
    if (atomicLoad(&listed.alone) == 0u) {
        return;
    }
    let n = atomicLoad(&listed.pixels);
    for (var i = invocation(wg, groups, local); i < n; i += groups.x * groups.y * GROUP) {
        if (atomicLoad(&work[flags_start() + i]) == 0u) {
            continue;
        }
        let at = listed.at[i];
        let pos = pixel_position(at);
        let c = candidates(pos);
        var tally = Tally(0, 0u, 0u, 0u);
        for (var e = c.first; e < c.end; e++) {
            let k = candidate(c, e);
            if (k != NONE) {
                add_piece(k, pixel_ndc(at), vec4<f32>(pos, 1.0), &tally);
            }
        }
        settle(at, tally);
    }
}
