"""Layer 5, the command line: argparse (`main`) and the human-readable answers (`text`)."""
