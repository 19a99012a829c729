//! Skeleton poses and affordance checks (in progress).
