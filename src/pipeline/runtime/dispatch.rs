//! The producer's end of a crossbar: which output port each item a unit sends leaves by.
//! The rule is the boundary's ([`crate::graph::Dispatch`]), chosen when the graph is
//! elaborated; the unit only says what it sends ([`super::Ctx::emit`]).

use std::ops::Range;

/// How a unit's items are spread over the consumers of the boundary its path takes.
pub struct Dispatcher<O> {
    /// The output ports of that boundary: one per consumer, in the consumers' order.
    ports: Range<usize>,
    rule: Rule<O>,
    /// The primitives per batch its consumers take, under a rule of batches.
    batch: Option<u32>,
    /// For the pipeline's source: the primitives an item carries, counted into the
    /// process-wide progress record ([`crate::progress`]) as the item leaves.
    progress: Option<fn(&O) -> u64>,
}

/// A dispatcher's rule.
enum Rule<O> {
    /// The n-th item to port `ports.start + n mod len`: `next` is the port of the next one.
    RoundRobin { next: usize },
    /// The consumer a function of the item names (the ROP owning its screen tile).
    Keyed(Box<dyn Fn(&O) -> usize>),
}

impl<O> Dispatcher<O> {
    /// Round-robin over `ports`, from its first (batches are items to it too: the n-th
    /// batch to the n-th consumer mod N).
    pub fn round_robin(ports: Range<usize>) -> Self {
        Dispatcher {
            rule: Rule::RoundRobin { next: ports.start },
            ports,
            batch: None,
            progress: None,
        }
    }

    /// Each item to the consumer `key(item)` names (a position among `ports`).
    pub fn keyed(ports: Range<usize>, key: impl Fn(&O) -> usize + 'static) -> Self {
        Dispatcher {
            ports,
            rule: Rule::Keyed(Box::new(key)),
            batch: None,
            progress: None,
        }
    }

    /// The same rule, dealing batches of `batch` primitives (the consumers' batch: the
    /// producer cuts its primitives into batches of it).
    pub fn with_batch(mut self, batch: Option<u32>) -> Self {
        self.batch = batch;
        self
    }

    /// The same rule, counting the primitives each item carries (`primitives`) into the
    /// progress record as it leaves: what a person watching sees advance.
    pub fn with_progress(mut self, primitives: fn(&O) -> u64) -> Self {
        self.progress = Some(primitives);
        self
    }

    /// The consumers' batch under a rule of batches; None otherwise.
    pub fn batch(&self) -> Option<u32> {
        self.batch
    }

    /// The consumers it spreads items over.
    pub fn consumers(&self) -> usize {
        self.ports.len()
    }

    /// The position among the consumers of the one the next item goes to, under a
    /// round-robin rule (for what a producer models per consumer, such as a setup engine's
    /// vertex cache); None under a keyed rule, where it depends on the item.
    pub fn next_consumer(&self) -> Option<usize> {
        match self.rule {
            Rule::RoundRobin { next } => Some(next - self.ports.start),
            Rule::Keyed(_) => None,
        }
    }

    /// The output port `item` leaves by, advancing the rule.
    #[inline(always)]
    pub fn port(&mut self, item: &O) -> usize {
        if let Some(primitives) = self.progress {
            crate::progress::advance(primitives(item));
        }
        match &mut self.rule {
            Rule::RoundRobin { next } => {
                let port = *next;
                // Without a division per item.
                *next = if port + 1 >= self.ports.end {
                    self.ports.start
                } else {
                    port + 1
                };
                debug_assert!(self.ports.contains(&port), "an item sent with no consumer");
                port
            }
            Rule::Keyed(key) => {
                let c = key(item);
                debug_assert!(c < self.ports.len());
                self.ports.start + c
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Round-robin goes through the ports in order and wraps, from the range's first.
    #[test]
    fn round_robin_cycles_through_its_ports() {
        let mut d = Dispatcher::<u32>::round_robin(2..5);
        let ports: Vec<usize> = (0..7).map(|n| d.port(&n)).collect();
        assert_eq!(ports, [2, 3, 4, 2, 3, 4, 2]);
        assert_eq!(d.next_consumer(), Some(1));
        assert_eq!(d.consumers(), 3);
    }

    /// A keyed rule sends each item to the consumer it names, offset by the range.
    #[test]
    fn keyed_sends_by_the_item() {
        let mut d = Dispatcher::<u32>::keyed(4..8, |&n| n as usize % 4);
        assert_eq!([5, 2, 7].map(|n| d.port(&n)), [5, 6, 7]);
        assert_eq!(d.next_consumer(), None);
    }
}
