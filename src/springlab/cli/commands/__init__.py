"""One module per `springlab` command: its options (`add_arguments`), the parsing of its strings, its call
of the library and its text (`main`). `springlab.cli.main.COMMANDS` lists them."""
