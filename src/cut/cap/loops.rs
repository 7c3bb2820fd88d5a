//! Cut loops: takes the directed cut segments (as the negative side's
//! triangles use them) and returns the closed loops they chain into, in cap
//! orientation, with the number of chains that do not close.

use std::collections::HashMap;

/// Loops of cut vertices from directed segments `a → b` (as the negative
/// side's triangles use them), each returned reversed (cap orientation).
/// Chains that do not close into a loop are counted as open.
pub fn loops(segments: &[(u32, u32)]) -> (Vec<Vec<u32>>, usize) {
    let mut succ: HashMap<u32, u32> = HashMap::with_capacity(segments.len());
    let mut bad = std::collections::HashSet::new();
    for &(a, b) in segments {
        // Cap direction: b → a.
        if succ.insert(b, a).is_some() {
            bad.insert(b);
        }
    }
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    // Open chains, walked from their heads (no predecessor): one each.
    let preds: std::collections::HashSet<u32> = succ.values().copied().collect();
    let mut heads: Vec<u32> = succ
        .keys()
        .filter(|v| !preds.contains(v))
        .copied()
        .collect();
    heads.sort_unstable();
    let mut open = heads.len();
    for h in heads {
        let mut v = h;
        while seen.insert(v) {
            match succ.get(&v) {
                Some(&w) => v = w,
                None => break,
            }
        }
    }
    let mut starts: Vec<u32> = succ.keys().copied().collect();
    starts.sort_unstable();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut lp = vec![s];
        seen.insert(s);
        let mut v = s;
        let closed = loop {
            if bad.contains(&v) {
                break false;
            }
            match succ.get(&v) {
                None => break false,
                Some(&w) if w == s => break true,
                Some(&w) => {
                    if !seen.insert(w) {
                        break false;
                    }
                    lp.push(w);
                    v = w;
                }
            }
        };
        if closed && lp.len() >= 3 {
            out.push(lp);
        } else {
            open += 1;
        }
    }
    (out, open)
}
