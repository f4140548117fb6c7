//! The executor's own cost per item: units that do no model work, so what is measured is
//! the runtime (links, merges, credits, scheduling). Issue 14's target was 40 ns or less
//! per item, issue 36's is 25 ns (RESULTS.md, "How cost grows").
//!
//! - `chain`: a source pushing N items through three forwarding units into a sink (four
//!   hops per item), FIFO depth 8.
//! - `merge`: four sources into one merging sink, FIFO depth 8 (one hop per item, the
//!   merge's bound checks included).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lembo_sim::pipeline::runtime::core::Core;
use lembo_sim::pipeline::runtime::executor::{HostThread, UnitFuture};
use lembo_sim::pipeline::runtime::link::{local_link, Ends, Rx, Tx};
use lembo_sim::pipeline::runtime::{Ctx, LinkName, LinkSpec};
use std::rc::Rc;

fn link(core: &Rc<Core>, p: u32, port: u32, c: u32) -> (Tx<u64>, Rx<u64>) {
    let name = LinkName {
        producer: core.slots[p as usize].name.clone(),
        consumer: core.slots[c as usize].name.clone(),
    };
    let spec = LinkSpec {
        fifo_depth: 8,
        latency_cycles: 1,
    };
    let ends = Ends {
        producer: p,
        port,
        consumer: c,
        from: p,
    };
    local_link(core, spec, name, ends, c as usize)
}

fn run(core: Rc<Core>, futures: Vec<UnitFuture<'_, u64>>) -> u64 {
    let n = futures.len();
    let (out, _) = HostThread {
        core,
        futures,
        global: (0..n).collect(),
        remotes: Vec::new(),
    }
    .run(None)
    .unwrap();
    out.iter().map(|(_, x)| x).sum()
}

fn chain(items: u64) -> u64 {
    let names = ["Source", "A", "B", "C", "Sink"];
    let core = Rc::new(Core::new(
        names.iter().map(|n| (n.to_string(), 1)).collect(),
    ));
    let links: Vec<(Tx<u64>, Rx<u64>)> = (0..4).map(|i| link(&core, i, 0, i + 1)).collect();
    let mut txs: Vec<Option<Tx<u64>>> = Vec::new();
    let mut rxs: Vec<Option<Rx<u64>>> = Vec::new();
    for (t, r) in links {
        txs.push(Some(t));
        rxs.push(Some(r));
    }
    let mut futures: Vec<UnitFuture<'_, u64>> = Vec::new();
    let mut src = Ctx::<(), u64>::new(
        core.clone(),
        0,
        Vec::new(),
        vec![txs[0].take().unwrap()],
        None,
    );
    futures.push(Box::pin(async move {
        for n in 0..items {
            src.emit(1, n).await;
        }
        src.finish();
        0
    }));
    for u in 1..4u32 {
        let mut c = Ctx::<u64, u64>::new(
            core.clone(),
            u,
            vec![rxs[u as usize - 1].take().unwrap()],
            vec![txs[u as usize].take().unwrap()],
            None,
        );
        futures.push(Box::pin(async move {
            while let Some(x) = c.next_input().await {
                c.emit(1, x).await;
            }
            c.finish();
            0
        }));
    }
    let mut sink = Ctx::<u64, ()>::new(
        core.clone(),
        4,
        vec![rxs[3].take().unwrap()],
        Vec::new(),
        None,
    );
    futures.push(Box::pin(async move {
        let mut sum = 0;
        while let Some(x) = sink.next_input().await {
            sum += x;
        }
        sink.finish();
        sum
    }));
    run(core, futures)
}

fn merge(items: u64) -> u64 {
    let core = Rc::new(Core::new(
        (0..5)
            .map(|i| {
                (
                    if i < 4 {
                        format!("Source[{i}]")
                    } else {
                        "Sink".into()
                    },
                    1,
                )
            })
            .collect(),
    ));
    let mut rxs = Vec::new();
    let mut futures: Vec<UnitFuture<'_, u64>> = Vec::new();
    for s in 0..4u32 {
        let (tx, rx) = link(&core, s, 0, 4);
        rxs.push(rx);
        let mut c = Ctx::<(), u64>::new(core.clone(), s, Vec::new(), vec![tx], None);
        futures.push(Box::pin(async move {
            for n in 0..items / 4 {
                // Sources of different speeds, so the merge interleaves them.
                c.emit(1 + (n + s as u64) % 3, n).await;
            }
            c.finish();
            0
        }));
    }
    let mut sink = Ctx::<u64, ()>::new(core.clone(), 4, rxs, Vec::new(), None);
    futures.push(Box::pin(async move {
        let mut sum = 0;
        while let Some(x) = sink.next_input().await {
            sum += x;
        }
        sink.finish();
        sum
    }));
    run(core, futures)
}

fn executor(c: &mut Criterion) {
    let mut g = c.benchmark_group("executor");
    let items = 100_000u64;
    // Four hops per item in the chain, one in the merge: throughput counts hops.
    g.throughput(Throughput::Elements(4 * items));
    g.bench_with_input(BenchmarkId::new("chain", items), &items, |b, &n| {
        b.iter(|| chain(n))
    });
    g.throughput(Throughput::Elements(items));
    g.bench_with_input(BenchmarkId::new("merge", items), &items, |b, &n| {
        b.iter(|| merge(n))
    });
    g.finish();
}

criterion_group!(benches, executor);
criterion_main!(benches);
