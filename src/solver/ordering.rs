//! Nested dissection of a sheet's graph by planes: each connected part is
//! cut at the median of its longest extent in the reference sheet, the
//! vertices on the cut that touch the other side are eliminated last, and
//! parts of at most [`ND_LEAF`] vertices (and every separator) are
//! ordered by minimum degree (faer's AMD).
//!
//! On large sheets this needs fewer multiply-adds and factor entries than
//! AMD on the whole graph; breadth-first level sets as separators (no
//! coordinates) need more than AMD, so without coordinates the solver
//! keeps AMD (`cargo bench --bench ordering`, docs/performance.md).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMat;

/// A graph as symmetric adjacency lists (CSR; self loops ignored).
pub struct Graph<'a> {
    /// Start of each vertex's neighbours in `adj` (`n + 1` entries).
    pub xadj: &'a [usize],
    /// Neighbours.
    pub adj: &'a [usize],
}

impl Graph<'_> {
    fn n(&self) -> usize {
        self.xadj.len() - 1
    }

    fn neighbours(&self, v: usize) -> &[usize] {
        &self.adj[self.xadj[v]..self.xadj[v + 1]]
    }
}

/// Parts of at most this many vertices are ordered by minimum degree
/// (16 to 128 give the same flops within 1 % on the pyramid).
pub const ND_LEAF: usize = 48;

/// Why no fill-reducing order was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrderingError {
    /// Nested dissection got a number of positions unlike the vertices'.
    PositionCount {
        /// Positions given.
        positions: usize,
        /// Vertices of the graph.
        vertices: usize,
    },
    /// No memory for faer's AMD workspace.
    OutOfMemory,
    /// faer's AMD failed.
    Amd(faer::sparse::FaerError),
}

impl std::fmt::Display for OrderingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OrderingError::PositionCount {
                positions,
                vertices,
            } => write!(
                f,
                "nested dissection: {positions} positions for {vertices} vertices"
            ),
            OrderingError::OutOfMemory => write!(f, "out of memory for the ordering"),
            OrderingError::Amd(e) => write!(f, "ordering failed: {e:?}"),
        }
    }
}

impl std::error::Error for OrderingError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            OrderingError::Amd(e) => Some(e),
            _ => None,
        }
    }
}

/// The nested-dissection order of the graph's vertices at positions
/// `coords` (`order[k]` is the vertex eliminated `k`-th).
pub fn nested_dissection(g: &Graph, coords: &[[f64; 3]]) -> Result<Vec<usize>, OrderingError> {
    let n = g.n();
    if coords.len() != n {
        return Err(OrderingError::PositionCount {
            positions: coords.len(),
            vertices: n,
        });
    }
    let mut nd = Dissection {
        g,
        x: coords,
        stamp: vec![0; n],
        side: vec![0; n],
        local: vec![0; n],
        counter: 0,
        order: Vec::with_capacity(n),
    };
    let mut stack = vec![Task::Order((0..n).collect())];
    while let Some(task) = stack.pop() {
        match task {
            Task::Order(set) => nd.order_set(set, &mut stack)?,
            Task::Last(sep) => nd.minimum_degree(&sep)?,
        }
    }
    debug_assert_eq!(nd.order.len(), n);
    Ok(nd.order)
}

/// Work left: a set to order, or a separator to append once the parts
/// before it are ordered.
enum Task {
    Order(Vec<usize>),
    Last(Vec<usize>),
}

struct Dissection<'g, 'a> {
    g: &'g Graph<'a>,
    x: &'g [[f64; 3]],
    /// `stamp[v] == counter` marks `v` as inside the set being worked on.
    stamp: Vec<u64>,
    /// Side of the cut being made (1 below the median, 2 at or above).
    side: Vec<u8>,
    /// Index of a vertex within the set being ordered by minimum degree.
    local: Vec<usize>,
    counter: u64,
    order: Vec<usize>,
}

impl Dissection<'_, '_> {
    /// Mark `set` as the current set (a fresh stamp).
    fn mark(&mut self, set: &[usize]) -> u64 {
        self.counter += 1;
        for &v in set {
            self.stamp[v] = self.counter;
        }
        self.counter
    }

    /// The part of the marked set connected to `root` (breadth first), and
    /// the fresh stamp its vertices now carry.
    fn component(&mut self, root: usize, mark: u64) -> (Vec<usize>, u64) {
        self.counter += 1;
        let seen_mark = self.counter;
        let mut seen = vec![root];
        self.stamp[root] = seen_mark;
        let mut head = 0;
        while head < seen.len() {
            let v = seen[head];
            head += 1;
            for &w in self.g.neighbours(v) {
                if self.stamp[w] == mark {
                    self.stamp[w] = seen_mark;
                    seen.push(w);
                }
            }
        }
        (seen, seen_mark)
    }

    /// Order `set`: push (in reverse) the tasks that order its parts and
    /// then its separator.
    fn order_set(&mut self, set: Vec<usize>, stack: &mut Vec<Task>) -> Result<(), OrderingError> {
        if set.len() <= ND_LEAF {
            return self.minimum_degree(&set);
        }
        let mark = self.mark(&set);
        // Connected components are ordered one after the other.
        let (first, connected) = self.component(set[0], mark);
        if first.len() < set.len() {
            let rest: Vec<usize> = set
                .iter()
                .copied()
                .filter(|&v| self.stamp[v] == mark)
                .collect();
            stack.push(Task::Order(rest));
            stack.push(Task::Order(first));
            return Ok(());
        }
        // The whole set is connected and carries the component's stamp.
        match self.cut(&set, connected) {
            Some((part, rest, sep)) => {
                stack.push(Task::Last(sep));
                stack.push(Task::Order(rest));
                stack.push(Task::Order(part));
                Ok(())
            }
            None => self.minimum_degree(&set),
        }
    }

    /// Cut a connected marked set at the median of its longest extent:
    /// `(one side, the other side without the separator, separator)`,
    /// the separator taken from the side where it is smaller; None if all
    /// its vertices are at one point.
    fn cut(&mut self, set: &[usize], mark: u64) -> Option<(Vec<usize>, Vec<usize>, Vec<usize>)> {
        let x = self.x;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &v in set {
            for d in 0..3 {
                lo[d] = lo[d].min(x[v][d]);
                hi[d] = hi[d].max(x[v][d]);
            }
        }
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &b| (hi[b] - lo[b]).total_cmp(&(hi[a] - lo[a])));
        for d in axes {
            if hi[d] <= lo[d] {
                break;
            }
            let mut vals: Vec<f64> = set.iter().map(|&v| x[v][d]).collect();
            let mid = vals.len() / 2;
            let (_, &mut m, _) = vals.select_nth_unstable_by(mid, f64::total_cmp);
            // Vertices at one point (a crease vertex's slots) stay together.
            let (mut below, mut above) = (Vec::new(), Vec::new());
            for &v in set {
                if x[v][d] < m {
                    self.side[v] = 1;
                    below.push(v);
                } else {
                    self.side[v] = 2;
                    above.push(v);
                }
            }
            if below.is_empty() || above.is_empty() {
                continue;
            }
            let touches = |nd: &Self, v: usize, other: u8| {
                nd.g.neighbours(v)
                    .iter()
                    .any(|&w| nd.stamp[w] == mark && nd.side[w] == other)
            };
            let nb = below.iter().filter(|&&v| touches(self, v, 2)).count();
            let na = above.iter().filter(|&&v| touches(self, v, 1)).count();
            let (side, other, mark_other) = if na <= nb {
                (above, below, 1)
            } else {
                (below, above, 2)
            };
            let (sep, rest): (Vec<usize>, Vec<usize>) =
                side.iter().partition(|&&v| touches(self, v, mark_other));
            return Some((other, rest, sep));
        }
        None
    }

    /// Append `set` in minimum-degree order of its induced subgraph.
    fn minimum_degree(&mut self, set: &[usize]) -> Result<(), OrderingError> {
        let m = set.len();
        if m <= 2 {
            self.order.extend_from_slice(set);
            return Ok(());
        }
        for (i, &v) in set.iter().enumerate() {
            self.local[v] = i;
        }
        let mark = self.mark(set);
        let mut col = Vec::with_capacity(m + 1);
        let mut row = Vec::new();
        col.push(0);
        for &v in set {
            row.push(self.local[v]);
            for &w in self.g.neighbours(v) {
                if self.stamp[w] == mark && w != v {
                    row.push(self.local[w]);
                }
            }
            col.push(row.len());
        }
        let fwd = amd(m, col, row)?;
        self.order.extend(fwd.iter().map(|&i| set[i]));
        Ok(())
    }
}

/// faer's AMD order of an `m x m` symmetric pattern (CSC, both triangles,
/// rows unsorted): `order[k]` is the index eliminated `k`-th.
pub(super) fn amd(m: usize, col: Vec<usize>, row: Vec<usize>) -> Result<Vec<usize>, OrderingError> {
    let nnz = row.len();
    let pat = SymbolicSparseColMat::new_unsorted_checked(m, m, col, None, row);
    let mut fwd = vec![0usize; m];
    let mut inv = vec![0usize; m];
    let mut mem = MemBuffer::try_new(faer::sparse::linalg::amd::order_maybe_unsorted_scratch::<
        usize,
    >(m, nnz))
    .map_err(|_| OrderingError::OutOfMemory)?;
    faer::sparse::linalg::amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        pat.as_ref(),
        Default::default(),
        MemStack::new(&mut mem),
    )
    .map_err(OrderingError::Amd)?;
    Ok(fwd)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The graph of an `m x m` grid (4-neighbours) and its positions.
    fn grid(m: usize) -> (Vec<usize>, Vec<usize>, Vec<[f64; 3]>) {
        let mut xadj = vec![0];
        let mut adj = Vec::new();
        let mut x = Vec::new();
        for i in 0..m {
            for j in 0..m {
                if i > 0 {
                    adj.push((i - 1) * m + j);
                }
                if j > 0 {
                    adj.push(i * m + j - 1);
                }
                if j + 1 < m {
                    adj.push(i * m + j + 1);
                }
                if i + 1 < m {
                    adj.push((i + 1) * m + j);
                }
                xadj.push(adj.len());
                x.push([j as f64, i as f64, 0.0]);
            }
        }
        (xadj, adj, x)
    }

    fn is_permutation(order: &[usize], n: usize) -> bool {
        let mut sorted = order.to_vec();
        sorted.sort_unstable();
        sorted == (0..n).collect::<Vec<_>>()
    }

    #[test]
    fn a_grid_is_cut_through_its_middle_line() {
        let m = 40;
        let (xadj, adj, x) = grid(m);
        let g = Graph {
            xadj: &xadj,
            adj: &adj,
        };
        let order = nested_dissection(&g, &x).unwrap();
        assert!(is_permutation(&order, m * m));
        // The last separator is one grid line: m vertices, all on x = 20.
        let last = &order[m * m - m..];
        assert!(last.iter().all(|&v| x[v][0] == 20.0), "{last:?}");
    }

    #[test]
    fn disconnected_parts_and_coincident_points_are_ordered() {
        // Two grids side by side with no edge between them, and the
        // second one's vertices all at one point.
        let (x1, a1, p1) = grid(20);
        let mut xadj = x1.clone();
        let mut adj = a1.clone();
        xadj.extend(x1[1..].iter().map(|&x| x + a1.len()));
        adj.extend(a1.iter().map(|&v| v + 400));
        let mut x = p1.clone();
        x.extend(std::iter::repeat_n([100.0, 0.0, 0.0], 400));
        let g = Graph {
            xadj: &xadj,
            adj: &adj,
        };
        let order = nested_dissection(&g, &x).unwrap();
        assert!(is_permutation(&order, 800));
        assert!(nested_dissection(&g, &x[..10]).is_err());
    }
}
