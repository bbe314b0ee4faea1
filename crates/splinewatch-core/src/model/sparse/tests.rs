use super::*;

/// The graph dissection orders every dof once, on a graph of two nets
/// joined by a few couplings with a point without dofs.
#[test]
fn the_graph_dissection_is_a_permutation() {
    let net = Pattern::control_net((40, 16), (3, 3), &[5; 640]);
    let mut graph: Vec<Vec<usize>> = net.graph().to_vec();
    graph.extend(
        net.graph()
            .iter()
            .map(|n| n.iter().map(|c| c + 640).collect::<Vec<_>>()),
    );
    // One net's last row of points coupled to the other's first.
    for j in 0..16 {
        let (a, b) = (39 * 16 + j, 640 + j);
        graph[a].push(b);
        graph[b].push(a);
    }
    graph.iter_mut().for_each(|n| n.sort_unstable());
    let mut counts = vec![5; 1280];
    counts[3] = 0; // a point without dofs is left out
    let joined = Pattern::control_graph(Arc::new(graph), &counts);
    assert!(!joined.is_single_net());
    let order = joined.nested_dissection();
    let mut seen = order.clone();
    seen.sort_unstable();
    assert_eq!(seen, (0..joined.dim()).collect::<Vec<_>>());
}

/// The same element matrices added into an accumulator and into a
/// matrix on the whole pattern give the same matrix, bit for bit, and
/// the accumulator holds only the columns it was given.
#[test]
fn an_accumulator_assembles_what_the_whole_pattern_does() {
    // A 6 × 4 net of bilinear elements (point (a, b) is number 4a + b),
    // 2 dofs per control point.
    let pattern = Arc::new(Pattern::control_net((6, 4), (1, 1), &[2; 24]));
    let mut whole = SparseSymmetric::zeros(Arc::clone(&pattern));
    let mut part = SparseAccumulator::new(Arc::clone(&pattern));
    for (i, j) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
        let points = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
        let mut dofs: Vec<usize> = points
            .iter()
            .flat_map(|&(a, b)| [2 * (a * 4 + b), 2 * (a * 4 + b) + 1])
            .collect();
        dofs.sort_unstable();
        let local = Mat::from_fn(8, 8, |r, c| {
            1.0 / (1.0 + r as f64 + c as f64) + 0.1 * (i + 2 * j) as f64
        });
        whole.add_local(&local, &dofs).unwrap();
        part.add_local(&local, &dofs).unwrap();
    }
    let built = part.to_matrix();
    assert!(built
        .values()
        .iter()
        .zip(whole.values())
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let held = part.columns.iter().filter(|c| c.is_some()).count();
    assert!(held < pattern.dim() / 2, "{held} of {} columns held", pattern.dim());
    assert!(whole.values().iter().any(|&v| v != 0.0));
}

/// `xᵀ A x` over `A`'s held columns equals `xᵀ (A x)` from `mul`, on a
/// matrix touching a corner of a 6 × 4 net only (1e-13 relative).
#[test]
fn the_quadratic_form_over_held_columns_is_the_products() {
    let pattern = Arc::new(Pattern::control_net((6, 4), (1, 1), &[2; 24]));
    let mut corner = SparseSymmetric::zeros(Arc::clone(&pattern));
    // The element of points (0,0), (1,0), (0,1), (1,1).
    let mut dofs: Vec<usize> = [0, 4, 1, 5].iter().flat_map(|&p| [2 * p, 2 * p + 1]).collect();
    dofs.sort_unstable();
    let local = Mat::from_fn(8, 8, |r, c| 1.0 / (1.0 + r as f64 + c as f64));
    corner.add_local(&local, &dofs).unwrap();
    let x = Mat::from_fn(pattern.dim(), 5, |r, c| ((r * 7 + c * 3) % 11) as f64 - 5.0);
    let a = corner.nonzeros();
    let (found, expected) = (a.quadratic(&x), x.transpose() * a.mul(&x));
    let scale = (0..5).map(|i| expected[(i, i)].abs()).fold(0.0, f64::max);
    assert!(scale > 0.0);
    for i in 0..5 {
        for j in 0..5 {
            assert!((found[(i, j)] - expected[(i, j)]).abs() <= 1e-13 * scale, "{i} {j}");
        }
    }
}
