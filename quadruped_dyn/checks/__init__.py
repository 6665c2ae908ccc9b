"""Every term compared with a reference: the term checks against Pinocchio, the cross-library
comparison, and the reference values of the generated C's check program."""
