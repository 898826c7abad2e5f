#!/bin/sh
# Build rcs-language-VERSION.vsix from this folder (needs Node.js and npm):
# installs the client library and vsce, then packages.  Install the result
# with `code --install-extension rcs-language-*.vsix`.
set -eu
cd "$(dirname "$0")"
npm install --no-audit --no-fund
npx vsce package --allow-missing-repository --skip-license
