//! Both TauLink ends — module and flight link code on the real radio driver over virtual Si4432s — running against each other in a simulated RF medium, in virtual time.
#![warn(missing_docs)]
