//! rodloop-continuation
