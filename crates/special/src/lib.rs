//! rodloop-special
