//! (filled in by the contact-geometry work)
