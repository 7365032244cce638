"""Pictures of results: PLY files and PNG figures a person can look at."""
