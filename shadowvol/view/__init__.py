"""`shadowvol view SCENE`: the interactive window for the lecture (see `app`)."""
