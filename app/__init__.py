"""The design studio: a viser web app over camcore (one Session per browser tab)."""
