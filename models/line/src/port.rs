//! The line's wiring at the bottom: a part's variable resolved once from its
//! value reference (`Port`), and a connection between two parts (`Link`).
//! Knows the parts' interfaces (their generated variable enums), not the parts.

/// A variable of a part, resolved from its value reference when the line is built
/// (`Part::port`), so that an evaluation goes straight to the part's field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Port {
    Span(converting_span::description::Real),
    Roller(roller::description::Real),
}

/// A connection, resolved to parts and value references.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    pub from: usize,
    pub output: u32,
    pub to: usize,
    pub input: u32,
    pub kind: LinkKind,
    /// `output` and `input` as the parts' own variables.
    pub source: Port,
    pub target: Port,
    /// A span's outputs are computed here, all at once: the first link in
    /// the evaluation order to read them after the last one that moved an
    /// input of the span (found when the line is built).
    pub fresh: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinkKind {
    Plain,
    /// A span's exit force into its exit roller, the span carrying web mass:
    /// one of the pulls of the network's `groups[group]`, all solved when the `lead` is evaluated.
    MassLoop { group: usize, lead: bool },
}
