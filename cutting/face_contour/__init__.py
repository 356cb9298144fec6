"""Face tooth contours by continuous indexing (seed 004): the slots, their removal and their exact measurement."""
