"""Design-side subcommands: geometry, export, sweep."""
