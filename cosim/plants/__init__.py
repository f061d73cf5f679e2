"""Python companions of the plant FMUs: closed forms and linear models (python-control)."""
