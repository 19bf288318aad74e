// The Bus Access Layer (chapter 4.1): IBalObject, its resources (one per bus connection) and
// OpenSocket, which gives the socket type asked for.
using System;
using System.Collections;
using System.Collections.Generic;
using Ixxat.Vci3.Bal.Can;
using Ixxat.Vci3.Bal.Lin;

namespace Ixxat.Vci3.Bal
{
  // What every socket is: a bus connection of a BAL.
  public interface IBalResource : IDisposable
  {
    byte BusPort { get; }
    VciBusType BusType { get; }
    string BusName { get; }
  }

  // One bus connection as IBalObject.Resources lists it.
  public sealed class BalResource
  {
    readonly byte port;
    readonly VciBusType type;
    readonly byte ctrl;
    internal BalResource(byte port, ushort word) { this.port = port; type = (VciBusType)(word >> 8); ctrl = (byte)word; }
    public byte BusPort { get { return port; } }
    public VciBusType BusType { get { return type; } }
    public byte ControllerType { get { return ctrl; } }
    public string BusName { get { return (type == VciBusType.Lin ? "LIN-" : "CAN-") + (port + 1); } }
    public override string ToString() { return BusName; }
  }

  public sealed class BalResourceCollection : IEnumerable<BalResource>
  {
    readonly BalResource[] items;
    internal BalResourceCollection(BalResource[] items) { this.items = items; }
    public int Count { get { return items.Length; } }
    public BalResource this[int index]
    {
      get
      {
        if (index < 0 || index >= items.Length)
          throw new VciException(Native.E_INVALIDARG, "BalResourceCollection[" + index + "]: the BAL has " + items.Length + " bus connections (0.." + (items.Length - 1) + ")");
        return items[index];
      }
    }
    public IEnumerator<BalResource> GetEnumerator() { return ((IEnumerable<BalResource>)items).GetEnumerator(); }
    IEnumerator IEnumerable.GetEnumerator() { return items.GetEnumerator(); }
  }

  public interface IBalObject : IDisposable
  {
    BalResourceCollection Resources { get; }
    Version FirmwareVersion { get; }
    // socketType: ICanSocket, ICanChannel, ICanControl, ICanScheduler, ILinSocket, ILinMonitor
    // or ILinControl; the object returned implements it.
    IBalResource OpenSocket(byte portIndex, Type socketType);
  }

  internal sealed class BalObject : IBalObject
  {
    IntPtr device;
    readonly string name;
    readonly BalResourceCollection resources;
    readonly Version firmware;

    internal BalObject(IntPtr device, string name)
    {
      this.device = device;
      this.name = name;
      var caps = new byte[Native.DeviceCapsSize];
      try { Native.Check(Native.vciDeviceGetCaps(device, caps), "IVciDevice.OpenBusAccessLayer"); }
      catch { Native.vciDeviceClose(device); throw; }
      var list = new BalResource[Math.Min((int)Bytes.U16(caps, 0), 32)];
      for (int i = 0; i < list.Length; i++) list[i] = new BalResource((byte)i, Bytes.U16(caps, 2 + 2 * i));
      resources = new BalResourceCollection(list);
      var info = new byte[Native.DeviceInfoSize];
      Native.vciDeviceGetInfo(device, info);
      firmware = new Version(info[24], info[25], Bytes.U16(info, 26));
    }

    internal IntPtr Device
    {
      get
      {
        if (device == IntPtr.Zero) throw VciException.Disposed("IBalObject");
        return device;
      }
    }
    internal string Name { get { return name; } }

    public BalResourceCollection Resources { get { var d = Device; return resources; } }
    public Version FirmwareVersion { get { var d = Device; return firmware; } }

    public IBalResource OpenSocket(byte portIndex, Type socketType)
    {
      var dev = Device;
      if (socketType == null) throw new VciException(Native.E_INVALIDARG, "IBalObject.OpenSocket: socketType is null");
      if (portIndex >= resources.Count)
        throw new VciException(Native.E_INVALIDARG, string.Format(
            "IBalObject.OpenSocket: port {0} does not exist; {1} has {2} bus connection(s), ports 0..{3}",
            portIndex, name, resources.Count, resources.Count - 1));
      var bus = resources[portIndex].BusType;
      bool lin = socketType == typeof(ILinSocket) || socketType == typeof(ILinMonitor) || socketType == typeof(ILinControl);
      bool can = socketType == typeof(ICanSocket) || socketType == typeof(ICanChannel) ||
                 socketType == typeof(ICanControl) || socketType == typeof(ICanScheduler);
      if (!lin && !can)
        throw new VciException(Native.E_INVALIDARG, "IBalObject.OpenSocket: " + socketType.FullName +
            " is no socket type (ICanSocket, ICanChannel, ICanControl, ICanScheduler, ILinSocket, ILinMonitor, ILinControl)");
      if (lin && bus != VciBusType.Lin || can && bus != VciBusType.Can)
        throw new VciException(Native.E_INVALIDARG, string.Format(
            "IBalObject.OpenSocket: port {0} of {1} is a {2} connection, not one for {3}", portIndex, name, bus, socketType.Name));
      if (socketType == typeof(ICanSocket)) return new CanSocket(this, portIndex);
      if (socketType == typeof(ICanChannel)) return new CanChannel(this, portIndex);
      if (socketType == typeof(ICanControl)) return new CanControl(this, portIndex);
      if (socketType == typeof(ICanScheduler)) return new CanScheduler(this, portIndex);
      if (socketType == typeof(ILinSocket)) return new LinSocket(this, portIndex);
      if (socketType == typeof(ILinMonitor)) return new LinMonitor(this, portIndex);
      return new LinControl(this, portIndex);
    }

    public void Dispose()
    {
      if (device != IntPtr.Zero) { Native.vciDeviceClose(device); device = IntPtr.Zero; }
    }
  }

  // What the sockets share: their BAL, port, and release of the daemon-side object.
  internal abstract class BalSocket : IBalResource
  {
    protected readonly BalObject bal;
    protected readonly byte port;
    protected readonly IntPtr device;
    protected volatile bool disposed;

    protected BalSocket(BalObject bal, byte port)
    {
      this.bal = bal;
      this.port = port;
      device = bal.Device;
    }

    public byte BusPort { get { return port; } }
    public abstract VciBusType BusType { get; }
    public string BusName { get { return (BusType == VciBusType.Lin ? "LIN-" : "CAN-") + (port + 1); } }
    protected abstract string Kind { get; }

    protected void Alive()
    {
      if (disposed) throw VciException.Disposed(Kind);
    }

    protected virtual void Release() { }

    public void Dispose()
    {
      if (disposed) return;
      disposed = true;
      Release();
      GC.SuppressFinalize(this);
    }

    ~BalSocket() { if (!disposed) { disposed = true; Release(); } }
  }
}
