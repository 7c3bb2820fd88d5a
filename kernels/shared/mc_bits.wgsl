// Shared by mc_classify, mc_vertices and mc_triangles: the inside flags of
// the padded grid's points as bit rows, written by mc_inside — bit x & 31
// of word x >> 5 of row y + ny·(z − z_first), row_words words a row, bits
// past nx zero; 1 where the sample is ≥ level (or equals the label). Each
// kernel reads them at binding 2 and passes its `params.rows`.
// Mirror: mc::grid::{BitRows, inside_bit, inside_run}.

struct BitRows {
    nx: u32,
    ny: u32,
    nz: u32,
    z_first: u32,    // first layer the words hold
    row_words: u32,  // words a row: ceil(nx / 32)
    unused0: u32,
    unused1: u32,
    unused2: u32,
}

@group(0) @binding(2) var<storage, read> inside_bits: array<u32>;

// The inside flag (0 or 1) of point (x, y, z).
fn inside(r: BitRows, x: u32, y: u32, z: u32) -> u32 {
    let word = inside_bits[(y + r.ny * (z - r.z_first)) * r.row_words + (x >> 5u)];
    return (word >> (x & 31u)) & 1u;
}

// The inside flags of points x, x + 1, x + 2 of row (y, z) as bits 0–2:
// one or two word reads; 0 past the row's end and for a row past the grid.
fn inside_run(r: BitRows, x: u32, y: u32, z: u32) -> u32 {
    if y >= r.ny || z >= r.nz {
        return 0u;
    }
    let at = (y + r.ny * (z - r.z_first)) * r.row_words + (x >> 5u);
    let s = x & 31u;
    var run = inside_bits[at] >> s;
    if s > 29u && (x >> 5u) + 1u < r.row_words {
        run |= inside_bits[at + 1u] << (32u - s);
    }
    return run & 7u;
}
