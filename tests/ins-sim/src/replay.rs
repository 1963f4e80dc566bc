//! PX4 replay format.
