#!/usr/bin/env bash
# Creates a DDS Security keystore laid out as ROS 2's SROS2 makes it (`ros2 security create_keystore` /
# `create_enclave`), with openssl only, for agvslamd's dds_security section and for ROS 2 nodes that read the pose
# (ROS_SECURITY_KEYSTORE=<keystore>, ROS_SECURITY_ENCLAVE_OVERRIDE=<enclave>, ROS_SECURITY_ENABLE=true,
# ROS_SECURITY_STRATEGY=Enforce).
#
#   deploy/make-keystore.sh [options] KEYSTORE [ENCLAVE:ROLE ...]
#
# Without ENCLAVE:ROLE arguments: /agvslam/agvslamd:daemon and /agvslam/reader:reader. A keystore that exists
# keeps its CA (new enclaves are signed by it); an enclave that exists is left alone unless --force.
#
# Roles (topic names as DDS sees them: ROS topic /<ns>/pose is rt/<ns>/pose):
#   daemon   agvslamd: publishes rt/<ns>/* (pose, odom, status) and rt/tf, rt/tf_static; subscribes to its inputs
#            rt/<ns>/in/*
#   reader   reads rt/<ns>/*, rt/tf and rt/tf_static only, publishes nothing of agvslam's (plus the topics every
#            ROS 2 node uses: ros_discovery_info, rt/rosout, rt/parameter_events and its parameter services)
#   input    publishes agvslamd's inputs rt/<ns>/in/* (e.g. a vehicle controller's wheel odometry)
#
# Options:
#   --namespace NS   topic namespace, agvslamd's dds.topic_namespace (default agvslam)
#   --domain ID      the only DDS domain the permissions allow (default: any of 0..230, the ids the DDS Security documents allow)
#   --days N         validity of the CA, the enclave certificates and the permissions (default 3650)
#   --force          recreate enclaves that exist (new key, certificate and permissions)
#
# Layout (SROS2's; the per-enclave CA and governance files are symbolic links, as SROS2 makes them):
#   KEYSTORE/public/ca.cert.pem               the CA certificate (identity and permissions CA are one CA)
#   KEYSTORE/public/{identity_ca,permissions_ca}.cert.pem -> ca.cert.pem
#   KEYSTORE/private/ca.key.pem               the CA's private key: keep it off the vehicle once enclaves exist
#   KEYSTORE/private/{identity_ca,permissions_ca}.key.pem -> ca.key.pem
#   KEYSTORE/enclaves/governance.{xml,p7s}    domain rules, signed by the permissions CA
#   KEYSTORE/enclaves/<enclave>/cert.pem, key.pem, permissions.{xml,p7s}, identity_ca.cert.pem,
#                               permissions_ca.cert.pem, governance.p7s
#
# Governance: no unauthenticated participants, join access control, discovery and liveliness encrypted, RTPS
# messages signed, every topic with read and write access control and encrypted data (the SROS2 defaults).
# Keys are ECDSA P-256 (what Cyclone DDS's and Fast DDS's built-in plugins accept besides RSA-2048).
set -euo pipefail

usage() { sed -n '2,35p' "$0"; }
die() {
  echo "make-keystore.sh: $*" >&2
  exit 2
}

ns=agvslam
domain=""
days=3650
force=0
keystore=""
enclaves=()
while [ $# -gt 0 ]; do
  case $1 in
    --namespace) ns=${2:?--namespace needs a value}; shift 2 ;;
    --domain) domain=${2:?--domain needs a value}; shift 2 ;;
    --days) days=${2:?--days needs a value}; shift 2 ;;
    --force) force=1; shift ;;
    -h | --help) usage; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *)
      if [ -z "$keystore" ]; then keystore=$1; else enclaves+=("$1"); fi
      shift
      ;;
  esac
done
[ -n "$keystore" ] || { usage >&2; exit 2; }
command -v openssl > /dev/null || die "openssl not found (apt-get install openssl)"
[[ $ns =~ ^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$ ]] ||
  die "--namespace: expected a ROS name without leading or trailing '/', e.g. agvslam, got '$ns'"
[[ $days =~ ^[1-9][0-9]*$ ]] || die "--days: expected a positive integer, got '$days'"
if [ -n "$domain" ]; then
  [[ $domain =~ ^[0-9]+$ ]] && [ "$domain" -le 230 ] || die "--domain: expected an integer in [0, 230] (DDS Security documents), got '$domain'"
fi
[ ${#enclaves[@]} -gt 0 ] || enclaves=("/$ns/agvslamd:daemon" "/$ns/reader:reader")

for spec in "${enclaves[@]}"; do  # all checked before anything is written
  [[ $spec == *:* ]] || die "$spec: expected ENCLAVE:ROLE, e.g. /$ns/agvslamd:daemon"
  [[ ${spec%:*} =~ ^(/[A-Za-z_][A-Za-z0-9_]*)+$ ]] ||
    die "${spec%:*}: expected an enclave name such as /agvslam/agvslamd ('/'-separated ROS names)"
  [[ ${spec##*:} =~ ^(daemon|reader|input)$ ]] || die "$spec: expected a role daemon, reader or input"
done

mkdir -p "$keystore"
keystore=$(cd "$keystore" && pwd)
pub=$keystore/public
priv=$keystore/private
encl=$keystore/enclaves
mkdir -p "$pub" "$priv" "$encl"
chmod 700 "$priv"
umask 077

# XML's five special characters, for names that go into the documents.
xml() {
  local s=$1
  s=${s//&/&amp;}
  s=${s//</&lt;}
  s=${s//>/&gt;}
  s=${s//\"/&quot;}
  s=${s//\'/&apos;}
  printf '%s' "$s"
}

# S/MIME clear-signed (detached, text mode) by the permissions CA: what the DDS Security plugins verify.
sign() {
  openssl smime -sign -text -in "$1" -out "$2" -signer "$pub/permissions_ca.cert.pem" \
    -inkey "$priv/permissions_ca.key.pem" -md sha256
}

if [ ! -f "$pub/ca.cert.pem" ]; then
  echo "make-keystore.sh: new CA in $keystore"
  openssl ecparam -name prime256v1 -genkey -noout -out "$priv/ca.key.pem"
  openssl req -new -x509 -sha256 -days "$days" -key "$priv/ca.key.pem" -out "$pub/ca.cert.pem" \
    -subj "/CN=agvslam keystore CA" \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature"
  chmod 644 "$pub/ca.cert.pem"
fi
[ -f "$priv/ca.key.pem" ] || die "$priv/ca.key.pem: the CA's private key is missing (needed to sign enclaves)"
for role in identity_ca permissions_ca; do
  ln -sfn ca.cert.pem "$pub/$role.cert.pem"
  ln -sfn ca.key.pem "$priv/$role.key.pem"
done

if [ -n "$domain" ]; then
  domains_xml="<domains><id>$domain</id></domains>"
else
  domains_xml="<domains><id_range><min>0</min><max>230</max></id_range></domains>"
fi

if [ ! -f "$encl/governance.p7s" ]; then
  cat > "$encl/governance.xml" << EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      $domains_xml
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
  sign "$encl/governance.xml" "$encl/governance.p7s"
  chmod 644 "$encl/governance.xml" "$encl/governance.p7s"
fi

topics_xml() {
  local t
  printf '<topics>'
  for t in "$@"; do printf '<topic>%s</topic>' "$(xml "$t")"; done
  printf '</topics>'
}

# ROS 2 node housekeeping topics (rcl creates them for every node; without them a secure ROS 2 node fails to start).
ros_pub=(ros_discovery_info rt/rosout rt/parameter_events "rr/*")
ros_sub=(ros_discovery_info rt/parameter_events "rq/*")

make_enclave() {
  local name=$1 role=$2
  local dir=$encl$name
  if [ -f "$dir/permissions.p7s" ] && [ $force -eq 0 ]; then
    echo "make-keystore.sh: $dir exists (kept; --force recreates it)"
    return
  fi
  local publish subscribe
  case $role in
    daemon)
      publish=$(topics_xml "rt/$ns/*" rt/tf rt/tf_static)
      subscribe=$(topics_xml "rt/$ns/in/*")
      ;;
    reader)
      publish=$(topics_xml "${ros_pub[@]}")
      subscribe=$(topics_xml "rt/$ns/*" rt/tf rt/tf_static "${ros_sub[@]}")
      ;;
    input)
      publish=$(topics_xml "rt/$ns/in/*")
      subscribe=""
      ;;
  esac
  mkdir -p "$dir"
  # The subject is CN=<enclave name>, as SROS2 writes it; '/' is escaped for openssl's -subj syntax.
  local subject="CN=$name"
  openssl ecparam -name prime256v1 -genkey -noout -out "$dir/key.pem"
  openssl req -new -sha256 -key "$dir/key.pem" -subj "/CN=${name//\//\\/}" -out "$dir/req.pem"
  openssl x509 -req -sha256 -days "$days" -in "$dir/req.pem" -CA "$pub/identity_ca.cert.pem" \
    -CAkey "$priv/identity_ca.key.pem" -set_serial "0x$(openssl rand -hex 16)" -out "$dir/cert.pem" \
    -extfile <(printf 'basicConstraints=CA:FALSE\nkeyUsage=critical,digitalSignature,keyAgreement\n') 2> /dev/null
  rm -f "$dir/req.pem"
  local not_before not_after
  not_before=$(date -u +%Y-%m-%dT%H:%M:%S)
  not_after=$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)
  {
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"'
    echo '     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">'
    echo '  <permissions>'
    echo "    <grant name=\"$(xml "$name")\">"
    echo "      <subject_name>$(xml "$subject")</subject_name>"
    echo "      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>"
    echo '      <allow_rule>'
    echo "        $domains_xml"
    [ -z "$publish" ] || echo "        <publish>$publish</publish>"
    [ -z "$subscribe" ] || echo "        <subscribe>$subscribe</subscribe>"
    echo '      </allow_rule>'
    echo '      <default>DENY</default>'
    echo '    </grant>'
    echo '  </permissions>'
    echo '</dds>'
  } > "$dir/permissions.xml"
  sign "$dir/permissions.xml" "$dir/permissions.p7s"
  # Relative links to the keystore's public files, as SROS2 makes them.
  local up
  up=$(realpath --relative-to="$dir" "$keystore")
  ln -sfn "$up/public/identity_ca.cert.pem" "$dir/identity_ca.cert.pem"
  ln -sfn "$up/public/permissions_ca.cert.pem" "$dir/permissions_ca.cert.pem"
  ln -sfn "$up/enclaves/governance.p7s" "$dir/governance.p7s"
  chmod 644 "$dir/cert.pem" "$dir/permissions.xml" "$dir/permissions.p7s"
  chmod 600 "$dir/key.pem"
  echo "make-keystore.sh: enclave $name ($role) in $dir"
}

for spec in "${enclaves[@]}"; do
  make_enclave "${spec%:*}" "${spec##*:}"
done
