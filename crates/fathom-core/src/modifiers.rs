//! Distance modifiers: operators on a node's list that act on the distance after the node's
//! subtree is evaluated (rounding, onion shells), rather than on the point.
//!
//! `k` is the distance scale at the node (see `transforms`), so lengths given in the node's
//! frame stay in that frame.

const BIG: f64 = 1e6;

crate::declare_family! {
    /// An operator on the distance value.
    family Modifier, noun "distance modifier", table MODIFIERS;
    fn modify(d: S, k: S) -> S;

    /// Rounds edges by `radius` (grows the shape by that much).
    Round [Bound] (radius: Scalar = 0.1, [0.0, BIG], "rounding radius") => d - radius * k;

    /// Turns the solid into a shell of the given thickness around its surface.
    Onion [Bound] (thickness: Scalar = 0.05, [0.0, BIG], "shell half-thickness")
        => d.abs() - thickness * k;
}
