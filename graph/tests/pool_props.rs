//! Property test over random DAGs: pool slots never join overlapping lifetimes, and every
//! pass runs after the writers of what it reads.

#[path = "support/fake.rs"]
mod fake;
use fake::*;
use meshlight_graph::*;
use proptest::prelude::*;

/// A random graph: pass i writes transient `t{i}` and reads up to three earlier ones; some
/// passes also write the imported `out`.
fn graph(reads: &[Vec<usize>], sizes: &[u64], to_out: &[bool]) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    let mut out = g.resource("out").unwrap();
    for (i, size) in sizes.iter().enumerate() {
        g.create_buffer(&format!("t{i}"), u32s(*size));
    }
    for (i, r) in reads.iter().enumerate() {
        out = synthetic::add_layer_pass(&mut g, i, r, to_out[i], out);
    }
    g
}

fn arb_graph() -> impl Strategy<Value = (Vec<Vec<usize>>, Vec<u64>, Vec<bool>)> {
    (2usize..40).prop_flat_map(|n| {
        let reads = (0..n)
            .map(|i| {
                if i == 0 {
                    Just(vec![]).boxed()
                } else {
                    proptest::collection::btree_set(0..i, 0..=3.min(i))
                        .prop_map(|s| s.into_iter().collect())
                        .boxed()
                }
            })
            .collect::<Vec<_>>();
        (
            reads,
            proptest::collection::vec(1u64..4096, n),
            proptest::collection::vec(proptest::bool::weighted(0.3), n),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn slots_never_share_overlapping_lifetimes_and_order_respects_writers((reads, sizes, to_out) in arb_graph()) {
        let plan = graph(&reads, &sizes, &to_out).compile(&opts()).unwrap().plan;
        // Overlapping lifetimes never share a slot.
        for a in 0..plan.resources.len() {
            for b in (a + 1)..plan.resources.len() {
                let (ra, rb) = (&plan.resources[a], &plan.resources[b]);
                if let (Some(sa), Some(sb), Some(la), Some(lb)) = (ra.pool_slot, rb.pool_slot, ra.lifetime, rb.lifetime) {
                    prop_assert!(sa != sb || !la.overlaps(&lb), "{} and {} share slot {sa}", ra.info.name, rb.info.name);
                }
            }
        }
        // Slot sizes cover every member.
        for slot in &plan.pool_slots {
            for &m in &slot.members {
                prop_assert!(slot.bytes >= plan.resources[m].info.desc.bytes());
            }
        }
        // Every pass runs after the writer of each version it reads.
        let pos = |p: usize| plan.order.iter().position(|&o| o == p);
        for &p in &plan.order {
            for s in plan.passes[p].slots.iter().filter(|s| s.access.reads() && s.version > 0) {
                let writer = plan.passes.iter().position(|q| q.slots.iter().any(|w| w.resource == s.resource && w.writes_version == Some(s.version))).unwrap();
                prop_assert!(pos(writer).unwrap() < pos(p).unwrap());
            }
        }
        prop_assert!(plan.bytes_with_reuse <= plan.bytes_without_reuse);
    }
}
