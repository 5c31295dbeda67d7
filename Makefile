# Shortcuts for ./dev, which does the real work (and its own set-up).
.PHONY: render test demo bench docs setup
render: ; ./dev render
test: ; ./dev test
demo: ; ./dev demo
bench: ; ./dev bench
docs: ; ./dev docs
setup: ; ./dev setup
