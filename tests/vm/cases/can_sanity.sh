# VM case: the kernel's vcan and can-raw modules load and can-utils carries frames (candump reads what cansend
# sent). The CAN driver's own real-bus test builds on this setup.
. "$(dirname "$0")/lib.sh"
step "modprobe vcan can-raw"
modprobe vcan || die "modprobe vcan"
modprobe can-raw || die "modprobe can-raw"
ip link add dev vcan0 type vcan || die "ip link add vcan0"
ip link set vcan0 up || die "ip link set vcan0 up"
ip -details link show vcan0
out=$VM_LOG_DIR/candump.txt
candump -L -n 3 vcan0 >"$out" &
dump=$!
sleep 0.5
cansend vcan0 123#DEADBEEF
cansend vcan0 5A1#0011223344556677
cansend vcan0 12345678#01
wait $dump || die "candump failed"
cat "$out"
frames=$(awk '{print $3}' "$out" | tr '\n' ' ')
[ "$frames" = "123#DEADBEEF 5A1#0011223344556677 12345678#01 " ] || die "candump read '$frames'"
echo "PASS: candump read the 3 frames cansend sent"
