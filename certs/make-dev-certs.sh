#!/usr/bin/env bash
# Makes development certificates for crackvis's mutual TLS (OpenSSL CLI):
# a CA, a server certificate for localhost / 127.0.0.1 / ::1, and client
# certificates, all signed by that CA. Keys are EC P-256, mode 0600; nothing
# here is ever committed (certs/generated/ is git-ignored).
#
#   certs/make-dev-certs.sh [DIR] [options]     DIR defaults to certs/generated
#
#   --client NAME    also make NAME.pem / NAME.key (CN = NAME), e.g. crackvis-render;
#                    repeatable. client.pem (CN crackvis-client) is always made.
#   --server-name N  add a DNS name to the server certificate's SANs (repeatable)
#   --days N         validity of new certificates (default 825)
#   --test-extras    also make what the tests need to see refused: other-ca.pem and
#                    other-client.pem/.key (signed by a second CA), and
#                    expired-client.pem/.key (signed by the CA, expired in 2021)
#   --force          replace existing files (by default an existing CA is reused,
#                    so certificates already handed out stay valid)
#
# Files: ca.pem ca.key server.pem server.key client.pem client.key [NAME.pem NAME.key ...]
set -euo pipefail

usage() { sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; }

dir=""
days=825
force=0
extras=0
clients=()
server_names=()
while (($#)); do
  case "$1" in
    --client) clients+=("${2:?--client needs a name}"); shift 2 ;;
    --server-name) server_names+=("${2:?--server-name needs a name}"); shift 2 ;;
    --days) days="${2:?--days needs a number}"; shift 2 ;;
    --test-extras) extras=1; shift ;;
    --force) force=1; shift ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "make-dev-certs: unknown option $1" >&2; usage >&2; exit 2 ;;
    *) [[ -z "$dir" ]] || { echo "make-dev-certs: one directory only" >&2; exit 2; }
       dir="$1"; shift ;;
  esac
done
if [[ -z "$dir" ]]; then
  dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/generated"
fi
command -v openssl >/dev/null || { echo "make-dev-certs: openssl not found (apt-get install openssl)" >&2; exit 1; }

umask 077
mkdir -p "$dir"
chmod 700 "$dir"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

new_key() {  # new_key FILE
  openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null
  chmod 600 "$1"
}

# make_ca NAME CN: NAME.pem + NAME.key, self-signed
make_ca() {
  new_key "$dir/$1.key"
  openssl req -x509 -new -key "$dir/$1.key" -sha256 -days "$days" -subj "/CN=$2" \
    -addext "basicConstraints=critical,CA:TRUE" \
    -addext "keyUsage=critical,keyCertSign,cRLSign" \
    -out "$dir/$1.pem" 2>/dev/null
}

# sign NAME CN CA EXTFILE: NAME.pem + NAME.key signed by CA(.pem/.key)
sign() {
  new_key "$dir/$1.key"
  openssl req -new -key "$dir/$1.key" -subj "/CN=$2" -out "$work/$1.csr" 2>/dev/null
  openssl x509 -req -in "$work/$1.csr" -CA "$dir/$3.pem" -CAkey "$dir/$3.key" \
    -CAcreateserial -CAserial "$work/$3.srl" -sha256 -days "$days" \
    -extfile "$4" -out "$dir/$1.pem" 2>/dev/null
}

client_ext="$work/client.ext"
cat >"$client_ext" <<EXT
basicConstraints=CA:FALSE
keyUsage=critical,digitalSignature,keyEncipherment
extendedKeyUsage=clientAuth
EXT

if ((force)) || [[ ! -s "$dir/ca.pem" || ! -s "$dir/ca.key" ]]; then
  make_ca ca "crackvis development CA"
fi

sans="DNS:localhost,IP:127.0.0.1,IP:::1"
for name in "${server_names[@]}"; do sans+=",DNS:$name"; done
server_ext="$work/server.ext"
cat >"$server_ext" <<EXT
basicConstraints=CA:FALSE
keyUsage=critical,digitalSignature,keyEncipherment
extendedKeyUsage=serverAuth
subjectAltName=$sans
EXT
sign server "crackvis-data" ca "$server_ext"
sign client "crackvis-client" ca "$client_ext"
for name in "${clients[@]}"; do
  sign "$name" "$name" ca "$client_ext"
done

if ((extras)); then
  make_ca other-ca "another CA"
  sign other-client "crackvis-client" other-ca "$client_ext"
  # An expired certificate needs explicit dates, which only 'openssl ca' sets.
  mkdir -p "$work/ca/new"
  : >"$work/ca/index.txt"
  cat >"$work/ca/openssl.cnf" <<CNF
[ca]
default_ca = dev
[dev]
database = $work/ca/index.txt
new_certs_dir = $work/ca/new
serial = $work/ca/serial
default_md = sha256
policy = any
x509_extensions = client
[any]
commonName = supplied
[client]
basicConstraints=CA:FALSE
keyUsage=critical,digitalSignature,keyEncipherment
extendedKeyUsage=clientAuth
CNF
  echo 01 >"$work/ca/serial"
  new_key "$dir/expired-client.key"
  openssl req -new -key "$dir/expired-client.key" -subj "/CN=crackvis-client" \
    -out "$work/expired.csr" 2>/dev/null
  openssl ca -batch -notext -config "$work/ca/openssl.cnf" -cert "$dir/ca.pem" \
    -keyfile "$dir/ca.key" -startdate 20200101000000Z -enddate 20210101000000Z \
    -in "$work/expired.csr" -out "$dir/expired-client.pem" 2>/dev/null
fi

chmod 600 "$dir"/*.key
chmod 644 "$dir"/*.pem
echo "make-dev-certs: certificates in $dir (CA: ca.pem; server: server.pem, SANs $sans)"
