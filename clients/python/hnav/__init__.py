"""Python client of HNAV runs: payload mirrors (`hnav.msg`) and joining a live run (`hnav.run`)."""
