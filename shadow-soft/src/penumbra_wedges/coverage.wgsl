// What one silhouette edge adds to a receiver's occluded share of the light (twin: coverage.rs, whose
// notes derive it).

const NEAR: f32 = 1e-3;
const PI: f32 = 3.14159265358979;

// ((a - p) x (b - p)) . (c - p): positive inside the side of the hard volume through edge a -> b.
fn side(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return dot(cross(a - p, b - p), c - p);
}

fn inside(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return select(0.0, 1.0, side(p, a, b, c) > 0.0);
}

// det(v - eye, c - eye, p - eye): the one expression both quads meeting at vertex v ask.
fn around(eye: vec3<f32>, v: vec3<f32>, c: vec3<f32>, p: vec3<f32>) -> f32 {
    return dot(cross(v - eye, c - eye), p - eye);
}

fn same(s: f32, reference: f32) -> bool {
    return (s > 0.0) == (reference > 0.0);
}

fn beyond(eye: vec3<f32>, a: vec3<f32>, b: vec3<f32>, x: vec3<f32>) -> f32 {
    return dot(cross(a - eye, b - eye), x - eye);
}

// Whether the eye's ray towards p meets the side quad of edge a -> b.
fn crosses_quad(p: vec3<f32>, eye: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> bool {
    return same(around(eye, a, c, p), around(eye, a, c, b))
        && same(around(eye, b, c, p), around(eye, b, c, a))
        && same(beyond(eye, a, b, p), beyond(eye, a, b, a + (a - c)));
}

// The side quad's z-pass step at p, per unit weight.
fn count_step(p: vec3<f32>, eye: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let step = inside(p, a, b, c) - inside(eye, a, b, c);
    if (step != 0.0 && crosses_quad(p, eye, a, b, c)) {
        return step;
    }
    return 0.0;
}

// The light as a receiver sees it (twin: Disc): w to the centre, its length and direction, and the
// disc's radius; seen is false inside the sphere.
struct Disc {
    w: vec3<f32>,
    dist: f32,
    axis: vec3<f32>,
    r: f32,
    seen: bool,
};

fn disc_seen_from(p: vec3<f32>, centre: vec3<f32>, radius: f32) -> Disc {
    var d: Disc;
    d.w = centre - p;
    d.dist = length(d.w);
    d.seen = d.dist > radius;
    d.axis = d.w / d.dist;
    d.r = radius * d.dist / sqrt(d.dist * d.dist - radius * radius);
    return d;
}

// The length of n's part in the light's plane, in disc radii.
fn across(d: Disc, n: vec3<f32>) -> f32 {
    return length(n - d.axis * dot(n, d.axis)) * d.r;
}

// A point of the edge cut where it comes `near` from the receiver along the axis.
fn cut(from_: vec3<f32>, z_from: f32, to: vec3<f32>, z_to: f32, near: f32) -> vec3<f32> {
    return from_ + (to - from_) * ((near - z_from) / (z_to - z_from));
}

// The signed share of the light's disc beyond edge a -> b seen from the centre, as p sees the edge.
fn wedge_area(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, centre: vec3<f32>, radius: f32) -> f32 {
    let disc = disc_seen_from(p, centre, radius);
    if (!disc.seen) {
        return 0.0;
    }
    let w = disc.w;
    let dist = disc.dist;
    let axis = disc.axis;
    let r = disc.r;
    let near = NEAR * dist;
    let za = dot(a - p, axis);
    let zb = dot(b - p, axis);
    if (za < near && zb < near) {
        return 0.0;
    }
    var a2 = a;
    var za2 = za;
    var b2 = b;
    var zb2 = zb;
    if (za < near) {
        a2 = cut(a, za, b, zb, near);
        za2 = near;
    }
    if (zb < near) {
        b2 = cut(b, zb, a, za, near);
        zb2 = near;
    }
    let pa = (a2 - p) * (dist / za2) - w;
    let pb = (b2 - p) * (dist / zb2) - w;
    let along = pb - pa;
    let len = length(along);
    if (len == 0.0) {
        return 0.0;
    }
    let dir = along / len;
    let sa = dot(pa, dir) / r;
    let sb = dot(pb, dir) / r;
    let across_ = across(disc, cross(a - p, b - p));
    let s = side(p, a, b, centre);
    if (across_ == 0.0) {
        return 0.0;
    }
    let magnitude = abs(s) / across_;
    if (magnitude >= 1.0) {
        return 0.0;
    }
    let h = select(-magnitude, magnitude, s > 0.0);
    let k = sqrt(1.0 - h * h);
    let s1 = min(max(-k, sa), sb);
    let s2 = min(max(k, sa), sb);
    let twice = -h * (s2 - s1) - (atan2(h, s2) - atan2(h, s1));
    return -twice / (2.0 * PI);
}

// wedge_area inside the edge's wedge planes, 0 without computing it outside (twin: wedge_term).
fn wedge_term(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, planes: array<vec4<f32>, 4>, centre: vec3<f32>, radius: f32) -> f32 {
    let q = vec4<f32>(p, 1.0);
    if (dot(planes[0], q) >= 0.0 && dot(planes[1], q) >= 0.0 && dot(planes[2], q) >= 0.0 && dot(planes[3], q) >= 0.0) {
        return wedge_area(p, a, b, centre, radius);
    }
    return 0.0;
}

// The share of the light's disc below the receiver's horizon (twin: horizon_share).
fn horizon_share(p: vec3<f32>, n: vec3<f32>, centre: vec3<f32>, radius: f32) -> f32 {
    let disc = disc_seen_from(p, centre, radius);
    if (!disc.seen) {
        return 0.0;
    }
    let width = across(disc, n);
    let above = dot(n, disc.w);
    if (width <= abs(above)) {
        return select(1.0, 0.0, above > 0.0);
    }
    let d = above / width;
    return (acos(d) - d * sqrt(1.0 - d * d)) / PI;
}
