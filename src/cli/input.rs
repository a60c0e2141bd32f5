//! Command-line options shared by every subcommand that reads a volume
//! (in progress: owned by the readers).
