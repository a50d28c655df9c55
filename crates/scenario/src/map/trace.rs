//! Tracing a grid's walls: the edges between solid and free cells, merged
//! into maximal straight segments.
//!
//! Every cell edge with a solid cell on one side and a free cell on the
//! other is part of the outline (outside the grid counts as solid, so the
//! map's border is closed). Consecutive edges on one grid line with the
//! free side on the same side are merged into one segment; a run ends where
//! the outline turns or where the free side changes (a corner where two
//! solid cells touch diagonally), so the segments join end to end into
//! closed outlines, one per boundary of a free region. Each segment is
//! directed with the free cells on its left: the outline of a free region
//! runs counter-clockwise, that of a solid island inside it clockwise.

/// A segment in grid units: cell `(i, j)` (column `i`, row `j` counted from
/// the bottom) spans `[i, i + 1] x [j, j + 1]`.
pub(crate) type GridSegment = [[u32; 2]; 2];

/// The outline of the cells for which `solid(i, j)` is true, in a grid of
/// `width` x `height` cells; see the module's documentation.
pub(crate) fn outline(
    width: usize,
    height: usize,
    solid: impl Fn(usize, usize) -> bool,
) -> Vec<GridSegment> {
    // Solid, with everything outside the grid solid.
    let at = |i: isize, j: isize| -> bool {
        i < 0
            || j < 0
            || i as usize >= width
            || j as usize >= height
            || solid(i as usize, j as usize)
    };
    let mut out = Vec::new();
    // Horizontal lines y = j: edge i lies between cells (i, j - 1) below and
    // (i, j) above. Side: +1 free above (run +x), -1 free below (run -x).
    for j in 0..=height as isize {
        let side = |i: isize| match (at(i, j - 1), at(i, j)) {
            (true, false) => 1,
            (false, true) => -1,
            _ => 0,
        };
        runs(width, side, |a, b, s| {
            let y = j as u32;
            out.push(if s > 0 {
                [[a, y], [b, y]]
            } else {
                [[b, y], [a, y]]
            });
        });
    }
    // Vertical lines x = i: edge j lies between cells (i - 1, j) left and
    // (i, j) right. Side: +1 free left (run +y), -1 free right (run -y).
    for i in 0..=width as isize {
        let side = |j: isize| match (at(i - 1, j), at(i, j)) {
            (false, true) => 1,
            (true, false) => -1,
            _ => 0,
        };
        runs(height, side, |a, b, s| {
            let x = i as u32;
            out.push(if s > 0 {
                [[x, a], [x, b]]
            } else {
                [[x, b], [x, a]]
            });
        });
    }
    out
}

/// Calls `emit(start, end, side)` for each maximal run of edges `0..n` with
/// the same non-zero side.
fn runs(n: usize, side: impl Fn(isize) -> i8, mut emit: impl FnMut(u32, u32, i8)) {
    let mut k = 0;
    while k < n {
        let s = side(k as isize);
        if s == 0 {
            k += 1;
            continue;
        }
        let start = k;
        while k < n && side(k as isize) == s {
            k += 1;
        }
        emit(start as u32, k as u32, s);
    }
}
